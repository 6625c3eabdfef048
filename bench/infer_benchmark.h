// The runtime measured end to end without trained models: a bundle with random weights on two
// procedural meshes, a sequence of deformed human frames on disk, and one run_inference over
// them. For Google Benchmark fixtures, scripts and tests; nothing here is needed to run a real
// bundle.
#pragma once

#include <cstdint>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "export/bundle_export.h"
#include "geometry/mesh.h"
#include "infer/infer_run.h"

namespace retarget {

struct RandomBundleOptions {
  // Both VAEs' architecture (models/mesh_vae.h defaults: the paper's sizes).
  std::vector<int64_t> channels{9, 128, 64, 64, 64, 1};
  int64_t hidden = 300;
  int64_t latent = 25;
  int64_t order = 2;          // Chebyshev order of every graph conv
  bool encoder_skip = false;  // the human encoder's linear input -> code path (models/mesh_vae.h)
  int64_t translation_hidden = 100;
  // Normaliser ranges: [-range, range] per (vertex, channel), widened by up to 10% at random, so
  // decoded features stay small rotations and stretches and reconstructions stay sane.
  double range = 0.1;
  uint64_t seed = 1;  // torch::manual_seed for the weights and ranges
  std::string human_name = "random-human", avatar_name = "random-avatar", avatar_units = "";
  // The avatar's rig (over avatar_rest, for retarget-infer --weights) and its still vertices
  // (BundleSide::still_vertices); none by default.
  std::optional<BundleRig> rig;
  std::vector<int> avatar_still_vertices;

  void validate() const;  // throws retarget::Error naming the option
};

// Writes a bundle (export/bundle_export.h) with randomly initialised human and avatar VAEs on
// the given rest meshes (cotangent DR options) and a random translation MLP into `folder`.
void write_random_bundle(const Mesh& human_rest, const Mesh& avatar_rest, const std::string& folder,
                         const RandomBundleOptions& options = {});

// `count` smooth deformations of `rest` (a travelling bulge plus a slow twist about +y, moving
// every vertex by up to a few percent of the bounding-box diagonal): a frame sequence.
std::vector<Positions> deformed_frames(const Mesh& rest, int count);

struct InferBenchmarkOptions {
  std::string folder;                           // scratch folder, emptied first; required
  int human_rings = 100, human_segments = 112;  // human: uv_sphere, 11,090 vertices
  int avatar_rings = 40, avatar_segments = 64;  // avatar: uv_sphere, 2,498 vertices
  int frames = 300;                             // human frames written as OBJ, frame_1.obj ...
  RandomBundleOptions bundle;                   // the random bundle (default sizes)
  InferOptions run;                             // bundle, inputs and out are filled in
};

// Writes folder/bundle and folder/input/frame_<k>.obj (emptying folder first) and returns
// options.run with bundle = folder/bundle, inputs = {folder/input} and out = folder/output: a run
// that can be repeated (run_inference) without writing the bundle and frames again.
InferOptions prepare_inference_benchmark(const InferBenchmarkOptions& options);

// run_inference(prepare_inference_benchmark(options)).
InferSummary run_inference_benchmark(const InferBenchmarkOptions& options);

}  // namespace retarget
