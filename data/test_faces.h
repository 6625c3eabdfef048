// The human meshes of a dataset's held-out people, written out as files: the inputs of the
// end-to-end check (`retarget faces`, then retarget-infer, then `retarget eval retarget`).
//
// out/<subject>_<expression>.obj   one mesh per (subject, expression), the human topology and
//                                  units of the dataset's source (face model or face folder)
// out/faces.yaml                   what they are:
//   format: retarget-faces
//   dataset: /abs/path/datasets/human      # the human dataset folder
//   fingerprint: 0123456789abcdef          # its topology fingerprint
//   recipes: /abs/path/facewarehouse47.yaml  # face-model datasets; empty for face folders
//   faces:
//     - {file: person003_smile.obj, subject: person003, expression: smile,
//        weights: {mouthSmile_L: 1.0, mouthSmile_R: 1.0}}   # recipe weights (face models only)
//     - {file: person003_blend004.obj, subject: person003, expression: blend004, set: blends,
//        weights: {jawOpen: 0.71, eyeBlink_L: 0.42}}       # an unseen blend (TestFacesOptions::blends)
//   A face without `set` is one of the references.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "geometry/expression_blends.h"

namespace retarget {

inline constexpr const char* kReferenceSet = "references";  // the dataset's own expressions
inline constexpr const char* kBlendSet = "blends";          // random blends nobody annotated

struct TestFacesOptions {
  std::string split = "test";            // "test", "train" or "all": whose subjects
  std::vector<std::string> subjects;     // by name; empty: every subject of the split
  std::vector<std::string> expressions;  // by name; empty: all of the dataset's
  bool force = false;                    // replace the files of a non-empty folder
  // Unseen expressions: blends.count random blends of the face model's shapes (the same blends
  // for every subject, none of them a reference recipe; face-model datasets only), in the set
  // "blends" beside the references.
  BlendOptions blends;
  bool references = true;  // write the dataset's expressions too (the set "references")
  void validate() const;   // throws retarget::Error naming "faces.<field>"
};

struct TestFace {
  std::string file;     // file name inside the folder
  std::string subject;  // Dataset::subjects entry
  std::string expression;
  std::map<std::string, double> weights;  // the recipe's blendshape weights (face models only)
  std::string set = kReferenceSet;        // kReferenceSet or kBlendSet
};

struct TestFaces {
  std::string folder;
  std::string dataset;      // the human dataset folder
  std::string fingerprint;  // its topology fingerprint
  std::string recipes;      // recipe file (face models), else empty
  std::vector<TestFace> faces;
  // The sets present, references first ("references", "blends").
  std::vector<std::string> sets() const;
};

// Writes the meshes and faces.yaml (atomically, faces.yaml last) of the human dataset folder
// `dataset` into `folder`. Face-model datasets rebuild each person from the stored identity
// coefficients; face-folder datasets copy the captured meshes. Throws retarget::Error for bad
// options, unknown subject or expression names (listing the known ones), or a non-empty
// folder without options.force.
TestFaces write_test_faces(const std::string& dataset, const std::string& folder, const TestFacesOptions& options = {});

// Reads folder/faces.yaml. Throws retarget::Error naming file:line and key for anything
// missing or malformed.
TestFaces load_test_faces(const std::string& folder);

}  // namespace retarget
