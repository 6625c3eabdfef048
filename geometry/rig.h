// Avatar rigs: a neutral mesh plus named controllers (blendshape targets), loaded from a
// folder with rig.yaml or from a glTF/GLB file whose morph targets are the controllers.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "geometry/mesh.h"
#include "geometry/metrics.h"

namespace retarget {

struct Controller {
  std::string name;
  Positions offset;         // #V x 3: target minus neutral (targets stored as absolute positions are converted)
  double min = 0, max = 1;  // weight range (rig.yaml `range: [min, max]`, default [0, 1])
};

struct Rig {
  std::string name;
  std::string source;        // the rig.yaml or .gltf/.glb path, for messages
  std::string units = "cm";  // informational: "cm", "mm", "m", ...
  Mesh neutral;
  std::vector<Controller> controllers;
  // Named landmark vertices (e.g. "nose_tip": 1234) used to pair this mesh with a human face
  // by name for deformation transfer; may be empty.
  std::map<std::string, int> landmarks;
  EyeLandmarks eyes;  // vertex sets around the two eyes (paper's unit convention); may be empty

  int controller_count() const { return static_cast<int>(controllers.size()); }
  int controller_index(const std::string& name) const;  // -1 if absent
  // neutral + sum_c weights[c] * offset_c. weights: #controllers. Returns #V x 3.
  // Weights are applied as given (not clamped to the ranges). Throws retarget::Error if
  // weights.size() != #controllers.
  Positions evaluate(const Eigen::VectorXd& weights) const;
};

// rig.yaml (paths relative to the file):
//   name: lapin                 # optional, default: the folder name
//   units: cm                   # optional
//   neutral: neutral.obj
//   targets: absolute           # or `offsets` (files hold target - neutral in their positions)
//   controllers:
//     - {name: smileLeft, file: smileLeft.obj, range: [0, 1]}   # range optional
//   landmarks: {nose_tip: 123, mouth_left: 456}                  # optional
//   eyes: {left: [..], right: [..]}                              # optional
// Target meshes must have the neutral's vertex count; their faces may differ (the neutral's
// connectivity is used). Throws retarget::Error naming the file and key for: a missing file,
// a target vertex count that differs (both counts and both files), duplicate controller
// names, a bad range (min >= max, not finite), landmark indices out of range, unknown keys.
// `rig_yaml_or_folder`: the rig.yaml itself or the folder holding it. Mesh paths are resolved
// against the yaml's folder (absolute paths stay); messages show them as resolved. A mesh the
// reader refuses is reported as "rig.yaml:<line>: <key>: <the reader's message>".
// Landmark and eye indices count from 0 and are checked against the neutral's vertex count.
Rig load_rig_folder(const std::string& rig_yaml_or_folder);

// glTF 2.0 (.gltf or .glb): the mesh named `mesh_name`, or if empty the mesh with the most
// morph targets; controllers are its morph targets (names from the mesh's extras.targetNames,
// else target_<k>), offsets from the POSITION deltas; ranges [0, 1]. The primitives of the
// mesh are merged into one vertex list. Throws retarget::Error for missing/invalid files, no
// mesh with morph targets, unknown mesh_name (listing the names), duplicate target names.
// Details: positions are the mesh's own (node transforms are not applied); units = "m" (glTF's
// unit); name = the file's stem; neutral.source = path. Primitives that share their POSITION
// and target accessors share their vertices; others are appended in order. Only triangle
// primitives (mode 4) are read (an error names the primitive otherwise); faces come from the
// indices (or 0, 1, 2, ... without them). Accessors may be float, or (normalised) integer
// components (KHR_mesh_quantization), strided, or sparse. A target without POSITION moves
// nothing. Wrong targetNames counts, out-of-range indices and out-of-bounds accessors are
// reported with the mesh, primitive and accessor.
Rig load_rig_gltf(const std::string& path, const std::string& mesh_name = "");

// Either of the above, by the path: a folder or .yaml -> load_rig_folder, .gltf/.glb -> glTF.
// A mesh_name with a rig folder, a missing path or another extension throws retarget::Error.
Rig load_rig(const std::string& path, const std::string& mesh_name = "");

// Writes `rig` as a folder: rig.yaml, neutral.obj and one <controller>.obj per controller
// (absolute positions), atomically per file. Used by `retarget synth`.
// File names keep a controller name's letters, digits, '-', '_' and '.', with '_' for
// anything else, made unique case-insensitively (and apart from neutral.obj) by _2, _3, ...;
// rig.yaml is written last, so a rig.yaml that exists names only complete meshes. Other files
// in the folder are left alone. Ranges other than [0, 1] are written with full precision.
void write_rig_folder(const std::string& folder, const Rig& rig);

}  // namespace retarget
