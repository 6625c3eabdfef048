// Avatar rigs: a neutral mesh plus named controllers (blendshape targets), loaded from a
// folder with rig.yaml (OBJ/PLY/OFF meshes, or a glTF/GLB file named by the yaml) or from a
// glTF/GLB file whose morph targets are the controllers; optionally with named parts (eyeballs,
// teeth, tongue) among the neutral's vertices.
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

// What a part of the avatar is, for code that has to find the eyeballs or the teeth (e.g. to
// keep them rigid, or to measure the eyes' distance). Sides are the character's own: in glTF
// (which faces +Z, +Y up) the left eye is the one at larger x.
enum class PartKind { eye_left, eye_right, teeth, tongue, other };
const char* to_string(PartKind kind);  // "eye_left", "eye_right", "teeth", "tongue", "other"

// A named set of the neutral's vertices: from a glTF mesh appended to the avatar (an eye mesh,
// the teeth) or from vertex indices in rig.yaml's `parts:`.
struct RigPart {
  std::string name;  // unique within the rig, e.g. "EyeLeft" or "teeth"
  PartKind kind = PartKind::other;
  std::string mesh;           // the glTF mesh it came from; empty for vertex lists
  std::vector<int> vertices;  // indices into Rig::neutral, ascending, distinct
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
  EyeLandmarks eyes;           // vertex sets around the two eyes (paper's unit convention); may be empty
  std::vector<RigPart> parts;  // may be empty; see PartKind
  // glTF rigs: the meshes the avatar was assembled from, in vertex order (the one with the
  // morph targets first); load_rig_gltf(source, {meshes, false}) reads the same avatar back.
  // Empty for rigs of OBJ/PLY/OFF files.
  std::vector<std::string> gltf_meshes;

  int controller_count() const { return static_cast<int>(controllers.size()); }
  int controller_index(const std::string& name) const;  // -1 if absent
  // The names of the controllers that move no vertex over their range (an offset zero at every
  // vertex, a target equal to the neutral: a placeholder morph; or a range of only 0), in
  // controller order. They are kept, so the weights' order
  // holds, but change nothing; the dataset and `avatar init` name them in a warning.
  std::vector<std::string> still_controllers() const;
  // neutral + sum_c weights[c] * offset_c. weights: #controllers. Returns #V x 3.
  // Weights are applied as given (not clamped to the ranges). Throws retarget::Error if
  // weights.size() != #controllers.
  Positions evaluate(const Eigen::VectorXd& weights) const;
};

// rig.yaml (paths relative to the file), with meshes as OBJ/PLY/OFF files:
//   name: lapin                 # optional, default: the folder name
//   units: cm                   # optional
//   neutral: neutral.obj
//   targets: absolute           # or `offsets` (files hold target - neutral in their positions)
//   controllers:
//     - {name: smileLeft, file: smileLeft.obj, range: [0, 1]}   # range optional
//   landmarks: {nose_tip: 123, mouth_left: 456}                  # optional
//   eyes: {left: [..], right: [..]}                              # optional
//   parts: {tongue: {kind: tongue, vertices: [[2000, 2099]]}}    # optional, see below
// or with the avatar in a glTF/GLB file (neutral/targets/controllers are then not allowed):
//   gltf: avatar.glb            # the controllers are its morph targets (load_rig_gltf)
//   mesh: Wolf3D_Head           # optional: the mesh with the morph targets (default: the most)
//   meshes: [Wolf3D_Head, EyeLeft, EyeRight, Wolf3D_Teeth]   # or: several meshes, one avatar
//   name: rpm                   # optional, default: the folder name
//   units: m                    # optional, default m (glTF's unit)
//   landmarks: {..}  eyes: {..}  parts: {..}                    # optional, as above
// With `meshes:` exactly those meshes make the avatar, the first holding the morph targets and
// each other one appended as a part; without it, eye/teeth/tongue meshes found by name are
// appended too (load_rig_gltf). Vertex indices (landmarks, eyes, parts) count over the whole
// avatar in that order: the first mesh's vertices, then each appended mesh's.
// parts: a map name -> {mesh: NAME} (a glTF mesh; appended to the avatar when not already in
// it) or {vertices: [i, [first, last], ...]} (indices, or inclusive ranges), with an optional
// `kind:` eye_left, eye_right, teeth, tongue or other (default: from the part's name, else the
// mesh's name, as load_rig_gltf recognises them; else other). Without `eyes:`, an eye_left and
// an eye_right part give the eyes (the eyeballs' vertices: their centroids are what
// millimetres_per_unit needs).
// Target meshes must have the neutral's vertex count; their faces may differ (the neutral's
// connectivity is used). Throws retarget::Error naming the file and key for: a missing file,
// a target vertex count that differs (both counts and both files), duplicate controller
// names, a bad range (min >= max, not finite), landmark indices out of range, unknown keys,
// neutral/controllers beside gltf:, unknown meshes (listing the file's), bad parts.
// `rig_yaml_or_folder`: the rig.yaml itself or the folder holding it. Mesh paths are resolved
// against the yaml's folder (absolute paths stay); messages show them as resolved. A mesh the
// reader refuses is reported as "rig.yaml:<line>: <key>: <the reader's message>".
// Landmark and eye indices count from 0 and are checked against the neutral's vertex count.
Rig load_rig_folder(const std::string& rig_yaml_or_folder);

// Which meshes of a glTF file make the avatar.
struct GltfRigOptions {
  // The meshes by name, the first holding the morph targets (the controllers), the others
  // appended to the avatar as parts, in this order. Empty: the mesh with the most morph
  // targets. A mesh without a name is named "#<index>" (its index in the file's meshes).
  std::vector<std::string> meshes;
  // With at most one mesh named: also append the meshes whose names say they are an eye, the
  // teeth or the tongue (see below), as parts of that kind, and fill Rig::eyes from the eyes.
  bool find_parts = true;
};

// glTF 2.0 (.gltf or .glb) -> a rig in the file's scene coordinates (metres, units = "m").
// Controllers are the first mesh's morph targets (names from the mesh's extras.targetNames,
// else target_<k>), offsets from the POSITION deltas; ranges [0, 1]. An appended mesh moves
// with the targets of the same name it has (matched by name; other targets leave it still);
// its targets that the first mesh lacks are ignored. The primitives of a mesh are merged into
// one vertex list; primitives that share their POSITION and target accessors share their
// vertices; others are appended in order.
// Node transforms: positions go through the world matrix (each node's matrix, or translation x
// rotation x scale, composed from the scene's roots) of the first node that instances the mesh,
// depth-first in the default scene (scene 0 without one; without scenes, from the nodes that
// are nobody's child): a mesh instanced by several nodes is read once, at its first instance. Morph deltas go through
// the matrix's linear part. A mesh no scene node instances is read in its own coordinates. Skinned meshes are read in
// their bind pose as glTF files store it: the mesh's own positions through its node's world matrix; the skin (joints,
// weights, inverse bind matrices) is not applied. Parts found by name (case-insensitive, the name split at '_', '.',
// '-', ':', spaces, digits and lower-to-upper case changes): a word eye/eyes/eyeball(s) with left/l or right/r
// (EyeLeft, eye_L, Eye.R, LeftEye, Eyeball_R, EyeL) -> eye_left/eye_right, unless another word says it is a lash, brow,
// lid, occlusion, tear line or shadow; teeth/tooth -> teeth; tongue -> tongue. An eye's side comes from its name; when
// both eyes' centroids say the opposite (the left eye at smaller x than the right one), a warning is logged and the
// names are kept. Part names are the mesh names. Throws retarget::Error for missing/invalid files, no mesh with morph
// targets, unknown mesh names (listing the names), a mesh named twice, duplicate target names, non-finite node
// transforms, node cycles, and compressed geometry (KHR_draco_mesh_compression,
// EXT_meshopt_compression) the chosen meshes need: naming the mesh, primitive and accessor.
// Only triangle primitives (mode 4) are read (an error names the primitive otherwise); faces
// come from the indices (or 0, 1, 2, ... without them). Accessors may be float, or (normalised)
// integer components (KHR_mesh_quantization), strided, or sparse. A target without POSITION
// moves nothing. Wrong targetNames counts, out-of-range indices and out-of-bounds accessors are
// reported with the mesh, primitive and accessor. name = the file's stem; neutral.source = path.
Rig load_rig_gltf(const std::string& path, const GltfRigOptions& options);
// The same with `mesh_name` as the only mesh (empty: the one with the most morph targets).
Rig load_rig_gltf(const std::string& path, const std::string& mesh_name = "");

// Either of the above, by the path: a folder or .yaml -> load_rig_folder, .gltf/.glb -> glTF.
// A mesh_name with a rig folder, a missing path or another extension throws retarget::Error.
Rig load_rig(const std::string& path, const std::string& mesh_name = "");
// The same, with glTF files read as exactly `gltf_meshes` (Rig::gltf_meshes of an earlier load;
// no parts found by name), so that a rig loads back as it was; empty: as load_rig(path). Rig
// folders (whose rig.yaml names its meshes) ignore `gltf_meshes`.
Rig load_rig(const std::string& path, const std::vector<std::string>& gltf_meshes);

// Writes `rig` as a folder: rig.yaml, neutral.obj and one <controller>.obj per controller
// (absolute positions), atomically per file. Used by `retarget synth`.
// File names keep a controller name's letters, digits, '-', '_' and '.', with '_' for
// anything else, made unique case-insensitively (and apart from neutral.obj) by _2, _3, ...;
// rig.yaml is written last, so a rig.yaml that exists names only complete meshes. Other files
// in the folder are left alone. Ranges other than [0, 1] are written with full precision.
void write_rig_folder(const std::string& folder, const Rig& rig);

}  // namespace retarget
