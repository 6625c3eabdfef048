// retarget-infer --rig-map MAP.yaml: the rig head at inference, without the network. Each
// frame's human blendshape weights - an ARKit take's frames (infer/arkit_take.h), or the face
// model fitted to each human mesh (geometry/face_model_fit.h: the mesh in the model's frame and
// units, as `retarget faces` writes them) - go through the map (geometry/controller_map.h) to
// the controller weights of the bundle's rig (format 3), clamped to their ranges; the avatar mesh
// is the rig at those weights. Outputs stay on the rig by construction, like DT on the rig.
//
// Written (atomically), named as the network path names them: OUT/<input stem>.<format> (a take:
// OUT/frame_<index, 6 digits>.<format> and OUT/frames.csv), OUT/weights.csv (frame,<controllers>:
// infer/weights_csv.h's table without residual_mm, which is 0 here), and with `gltf` the frames
// as a glTF morph-target animation at `fps`. A mesh that cannot be read, or is not of the face
// model's topology, stops the run with its message (before that, the files already written stay).
#pragma once

#include <string>
#include <vector>

namespace retarget {

struct RigHeadRunOptions {
  std::string bundle;               // a bundle with a rig (format 3), required
  std::string rig_map;              // map.yaml (`retarget rig-map fit`), required
  std::string face_model;           // face_model.yaml or its folder, required: the map's shapes are its
  std::string arkit;                // an ARKit take; or
  std::vector<std::string> inputs;  // human meshes: files, folders, glob patterns (infer/input_files.h)
  std::string out;                  // output folder, created if needed, required
  std::string format = "obj";       // of the meshes: "obj" or "ply"
  std::string gltf;                 // also a glTF animation (.glb or .gltf); "": none
  double fps = 30;                  // of the glTF animation; 0.001..100000

  // Throws retarget::Error naming the option (--bundle, --rig-map, --face-model, --arkit, --out,
  // --format).
  void validate() const;
};

struct RigHeadRunSummary {
  std::string out;
  std::string avatar;                // the rig's name
  int frames = 0;                    // meshes written
  int controllers = 0;               // the rig's
  int pairs = 0;                     // annotated pairs the map was fitted to
  std::vector<std::string> outputs;  // the meshes, in input order
  std::string weights_csv;           // OUT/weights.csv
  std::string gltf;                  // with gltf: the file
  double seconds = 0;                // the whole run
};

// Runs the above. Throws retarget::Error for invalid options, a bundle without a rig, a map
// whose controllers are not the rig's or whose shapes the face model lacks, a face model whose
// neutral is not the bundle's human topology, and the first input that fails.
RigHeadRunSummary run_rig_head(const RigHeadRunOptions& options);

// "rig head: 120 frames onto fox (14 controllers, a map of 47 pairs) in 0.84 s -> OUT ..."
std::string format_rig_head_summary(const RigHeadRunSummary& summary);

}  // namespace retarget
