// A set of captured human faces on disk: a folder of subjects, each a folder of expression
// meshes `<folder>/<subject>/<expression>.obj` (or .ply, .off), all of one topology and every
// subject with the same expressions (FaceWarehouse's layout, one file per pose).
#pragma once

#include <string>
#include <vector>

#include "geometry/mesh.h"

namespace retarget {

struct FaceFolderOptions {
  // The expression whose mesh is each subject's neutral face; when no subject has a mesh of
  // this name the folder has no neutral (FaceFolder::neutral == -1). Empty: never a neutral.
  std::string neutral = "neutral";
};

struct FaceFolder {
  std::string root;                      // the folder as given
  std::vector<std::string> subjects;     // subfolder names, sorted
  std::vector<std::string> expressions;  // file names without extension, sorted, the neutral first
  int neutral = -1;                      // index of the neutral in `expressions`, -1 when absent
  Mesh topology;  // the first mesh (subjects[0], expressions[0]): the connectivity every mesh must share

  int subject_index(const std::string& name) const;     // -1 if absent
  int expression_index(const std::string& name) const;  // -1 if absent
  // The file of one subject's expression.
  const std::string& path(int subject, int expression) const;
  // Reads that mesh: #V x 3 positions in the file's units. Throws retarget::Error naming the
  // file when it cannot be read or its topology differs from `topology` (both files, both counts).
  Positions read(int subject, int expression) const;

  std::vector<std::string> paths;  // [subject * #expressions + expression]
};

// Lists the folder and reads the first mesh; the other meshes are read (and checked) on demand,
// since a full capture set does not fit in memory. Throws retarget::Error naming the folder for:
// a missing folder, no subject folders, a subject with no meshes, two files of one expression
// (e.g. smile.obj and smile.ply), and subjects whose expression sets differ (listing what is
// missing where).
FaceFolder open_face_folder(const std::string& folder, const FaceFolderOptions& options = {});

}  // namespace retarget
