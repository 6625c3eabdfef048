// Shared pieces of the runtime tests: a tiny random bundle on two small meshes of different
// topologies, frames of human expressions on disk, and the in-framework pipeline to compare with.
#pragma once

#include <torch/script.h>
#include <torch/torch.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "bench/infer_benchmark.h"
#include "export/bundle_export.h"
#include "geometry/dr_features.h"
#include "geometry/mesh_io.h"
#include "geometry/reconstruction.h"
#include "tests/test_support.h"

namespace retarget::test {

// Human: a curved quad patch, 11 x 13 = 143 vertices, 120 quads (a stand-in for a face).
inline Mesh human_patch() {
  return quad_grid(10, 12, 2.0, 2.4, [](double x, double y) { return 0.4 * std::exp(-(x - 1) * (x - 1) - y * y); });
}

// Avatar: a UV sphere, 2 + 9 * 16 = 146 vertices.
inline Mesh avatar_ball() { return uv_sphere(10, 16, 1.5); }

// Small VAEs and F with random weights; features stay within +-0.1 (small rotations, stretches).
inline RandomBundleOptions tiny_bundle_options() {
  RandomBundleOptions options;
  options.channels = {9, 8, 1};
  options.hidden = 16;
  options.latent = 4;
  options.translation_hidden = 8;
  options.seed = 7;
  options.human_name = "patch";
  options.avatar_name = "ball";
  return options;
}

inline std::string tiny_bundle(const std::filesystem::path& folder) {
  write_random_bundle(human_patch(), avatar_ball(), folder.string(), tiny_bundle_options());
  return folder.string();
}

// Writes deformed human frames folder/<prefix><number>.obj (frame k of a 12-frame sequence for
// number k) and returns their paths in the order of `numbers`.
inline std::vector<std::string> write_frames(const std::filesystem::path& folder, const std::vector<int>& numbers,
                                             const std::string& prefix = "frame_") {
  const Mesh human = human_patch();
  const std::vector<Positions> frames = deformed_frames(human, 12);
  std::vector<std::string> paths;
  for (const int k : numbers) {
    const std::string path = (folder / (prefix + std::to_string(k) + ".obj")).string();
    write_mesh(path, with_positions(human, frames[k % frames.size()]));
    paths.push_back(path);
  }
  return paths;
}

// The in-framework pipeline for one mesh: DR features -> bundle forward -> reconstruction (-> align).
inline Positions expected_output(const LoadedBundle& bundle, const Positions& human, bool align_to_rest = true) {
  const DrFeatures dr(bundle.human_rest, bundle.metadata.human.dr);
  DrFeatureMatrix features = dr.compute(human);
  const torch::Tensor x = torch::from_blob(features.data(), {1, features.rows(), kDrWidth}, torch::kFloat32).clone();
  torch::jit::Module module = bundle.module;
  torch::NoGradGuard no_grad;
  const torch::Tensor y = module.forward({x}).toTensor().contiguous();
  ReconstructionOptions options;
  options.weighting = bundle.metadata.avatar.dr.weighting;
  options.align_to_rest = align_to_rest;
  return Reconstruction(bundle.avatar_rest, options).reconstruct(y.data_ptr<float>());
}

inline double max_difference(const Positions& a, const Positions& b) {
  if (a.rows() != b.rows()) return INFINITY;
  return (a - b).cwiseAbs().maxCoeff();
}

inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

}  // namespace retarget::test
