// A controller-weight sequence on an avatar rig as a glTF 2.0 animation: the avatar's neutral
// mesh with one morph target per controller and one animation that drives the morph weights
// over time, the form in which engines (Unity, Unreal, Blender, three.js) play blendshapes.
//
// The file holds one mesh (one triangle primitive: POSITION with min/max, NORMAL computed from
// the neutral, UNSIGNED_INT indices; one morph target of POSITION deltas with min/max per
// controller; mesh.weights all 0; mesh.extras.targetNames = the controller names), one node
// and one scene holding it, and one animation with a `weights` channel on the node: sampler
// input = the frame times in seconds (FLOAT SCALAR, min/max), output = F x C FLOAT weights in
// frame order, LINEAR interpolation. load_rig_gltf (geometry/rig.h) reads the mesh back as a
// rig with the same controllers.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "geometry/mesh.h"
#include "geometry/rig.h"

namespace retarget {

struct GltfAnimationInput {
  Mesh neutral;                          // #V x 3 rest positions in `units`; polygon faces (fanned to triangles)
  std::vector<std::string> controllers;  // C names, unique, non-empty (the morph targets' names)
  std::vector<Positions> offsets;        // C, each #V x 3: target minus neutral, in `units`
  std::vector<Eigen::VectorXd> weights;  // F frames, each C controller weights (applied as given)
  std::vector<double> times;             // F seconds, >= 0, strictly increasing; empty: frame k at k / fps
  std::string units = "cm";              // the mesh's units: "cm", "mm", "m", or "" (unknown: kept as they are)
};

struct GltfAnimationOptions {
  double fps = 30;  // frames per second when the input has no times; 0.001..100000
  // Metres per unit of the input (glTF is in metres): 0.01 for cm. Unset: from the input's
  // units (cm 0.01, mm 0.001, m 1; "" keeps the coordinates as they are; others are refused).
  std::optional<double> scale_to_metres;
  std::string mesh_name = "avatar";         // the glTF mesh's and node's name
  std::string animation_name = "retarget";  // the glTF animation's name
  void validate() const;                    // throws retarget::Error naming the option
};

// The input for `rig` (its neutral, controller names, offsets and units) and frames of weights
// (F, each #controllers; not checked here: write_gltf_animation checks them).
GltfAnimationInput gltf_animation_input(const Rig& rig, std::vector<Eigen::VectorXd> weights,
                                        std::vector<double> times = {});

// The metres per input unit that write_gltf_animation applies (options.scale_to_metres, else
// from units). Throws retarget::Error for unknown units without scale_to_metres.
double gltf_scale_to_metres(const std::string& units, const GltfAnimationOptions& options);

// What write_gltf_animation wrote, for a summary line.
struct GltfAnimationSummary {
  int vertices = 0, triangles = 0, controllers = 0, frames = 0;
  double duration = 0;         // seconds: the last frame's time
  double scale_to_metres = 1;  // as applied
  size_t bytes = 0;            // the file's size
};

// Writes `input` to `path`: binary glTF for .glb, glTF JSON with the buffer embedded as a base64
// data URI for .gltf (the extension decides, in any case). Positions and offsets are multiplied
// by the scale (gltf_scale_to_metres) and stored as float. Written atomically
// (core/atomic_file.h). Throws retarget::Error naming what is wrong for: an empty mesh (no
// vertices or faces), non-finite positions, face indices out of range, no controllers, offsets
// whose count or #V x 3 size differ, non-finite offsets, empty or duplicate controller names,
// no frames, a frame whose weight count is not C (naming the frame), non-finite weights or
// weights or times beyond a float's range (frame and controller), times whose count is not F, negative, non-finite or
// not strictly increasing times (in seconds or once stored as float), bad options, another extension.
GltfAnimationSummary write_gltf_animation(const GltfAnimationInput& input, const GltfAnimationOptions& options,
                                          const std::string& path);

}  // namespace retarget
