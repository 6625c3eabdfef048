// A loaded bundle ready to run: human meshes -> DR features -> bundle.pt -> avatar DR features ->
// avatar meshes. Everything that depends only on the two rest meshes (the human DR setup, the
// avatar's reconstruction factorisation) is done once, in the constructor; each stage is a method
// of its own, so a benchmark or a streaming caller can time or overlap them.
#pragma once

#include <torch/torch.h>

#include <memory>
#include <string>
#include <vector>

#include "bundle/bundle_format.h"
#include "geometry/dr_features.h"
#include "geometry/mesh.h"
#include "geometry/reconstruction.h"
#include "infer/retargeter_network.h"

namespace retarget {

struct RetargeterOptions {
  // Rigidly align every output to the avatar rest pose (rotation + translation, as the authors
  // did); off: each connected part keeps its rest centroid and the rotation the features imply.
  bool align_to_rest = true;
  // Hold the avatar's still vertices (the bundle's avatar.still_vertices) at rest; then the
  // outputs are in the rest's frame already and align_to_rest has nothing to do.
  bool anchors = true;
  // Move the avatar's rigid parts (eyeballs, teeth: the pieces apart from its skin) where its rig
  // puts them for the reconstructed skin (geometry/part_motion.h); bundles without a rig
  // (format < 3) keep each part at its rest centroid.
  bool part_motion = true;
  int threads = 0;  // OpenMP threads of the DR features and the reconstruction; 0 = all cores
  // Run the human encoder's graph convs natively (infer/retargeter_network.h: the same sums,
  // cache-blocked, ~2x faster at the paper's sizes); off: the bundle's scripted forward.
  bool native_network = true;
  // With native_network: the graph convs' dense products in float32, bfloat16 (where the CPU has
  // AVX512-BF16) or 8 bits (where it has AVX512-VNNI); infer/retargeter_network.h. The codes differ
  // from float32's by ~0.04% in bfloat16 and ~1% in int8 (tests/infer bounds them). Ignored elsewhere.
  NetworkPrecision precision = NetworkPrecision::float32;
  void validate(const std::string& key_path = "retargeter") const;  // throws retarget::Error
};

class Retargeter {
 public:
  // Sets up the human DR features (with the bundle's human DR options) and factorises the
  // avatar's reconstruction (with the avatar's edge weighting).
  explicit Retargeter(LoadedBundle bundle, const RetargeterOptions& options = {});

  const LoadedBundle& bundle() const { return bundle_; }
  const RetargeterOptions& options() const { return options_; }
  int human_vertices() const { return bundle_.human_rest.vertex_count(); }    // Vh
  int avatar_vertices() const { return bundle_.avatar_rest.vertex_count(); }  // Va
  bool native_network() const { return native_network_ != nullptr; }          // translate runs natively
  // What the network's products ran in: the option's precision where the CPU has it, else float32.
  NetworkPrecision precision() const {
    return native_network_ ? native_network_->precision() : NetworkPrecision::float32;
  }

  // human: B >= 1 meshes' positions, #Vh x 3 each, in the human rest's vertex order (any pose,
  // the rest's units). Returns [B, Vh, 9] float32 raw DR features against the bundle's human rest.
  // Throws retarget::Error for a vertex count other than Vh.
  torch::Tensor features(const std::vector<const Positions*>& human) const;

  // [B, Vh, 9] float32 raw human DR features -> [B, Va, 9] float32 raw avatar DR features: one
  // bundle.pt forward under torch::InferenceMode (no sampling: codes are encoder means), with the
  // encoder's graph convs run natively unless options.native_network is off.
  torch::Tensor translate(const torch::Tensor& human_features);

  // [B, Va, 9] raw avatar DR features -> B meshes' positions, #Va x 3 each, in the avatar rest's
  // units and frame (aligned to its rest pose unless options.align_to_rest is off).
  std::vector<Positions> reconstruct(const torch::Tensor& avatar_features) const;

  // The three stages in a row.
  std::vector<Positions> retarget(const std::vector<const Positions*>& human);

 private:
  LoadedBundle bundle_;
  RetargeterOptions options_;
  DrFeatures human_features_;
  Reconstruction avatar_reconstruction_;
  std::shared_ptr<const NativeNetwork> native_network_;  // null: the scripted forward
};

}  // namespace retarget
