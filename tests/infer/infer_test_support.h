// Shared pieces of the runtime tests: a tiny random bundle on two small meshes of different
// topologies, frames of human expressions on disk, and the in-framework pipeline to compare with.
#pragma once

#include <sys/wait.h>
#include <torch/script.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "bench/infer_benchmark.h"
#include "export/bundle_export.h"
#include "geometry/dr_features.h"
#include "geometry/mesh_io.h"
#include "geometry/reconstruction.h"
#include "tests/bump_rig.h"
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

// avatar_ball() at twice the resolution: 2 + 19 x 32 = 610 vertices. The rig bundle's avatar,
// fine enough for the reconstruction to keep the rig's bumps (on avatar_ball() it flattens them
// by a few percent, which the weights then show).
inline Mesh fine_ball() { return uv_sphere(20, 32, 1.5); }

// A rig on a ball of radius 1.5 (avatar_ball() by default): five smooth bumps along the normal around spots on the
// front (+z) half (overlapping a little), in the ranges [0, 1], [0, 1], [-1, 1], [0, 2], [0, 1], and a sideways shear
// of the upper (+y) front; the back (-z) moves for no controller. 10 mm per unit.
inline BundleRig ball_rig(const Mesh& ball = avatar_ball()) {
  BundleRig part;
  Rig& rig = part.rig;
  rig.name = "ball";
  rig.source = "ball/rig.yaml";
  rig.neutral = ball;
  const Positions& n = rig.neutral.vertices;
  const std::vector<Eigen::RowVector3d> spots{
      {0, 0.7, 0.7}, {0.7, 0, 0.7}, {-0.7, 0, 0.7}, {0.25, 0.3, 0.9}, {0, -0.6, 0.8}};
  const std::vector<std::pair<double, double>> ranges{{0, 1}, {0, 1}, {-1, 1}, {0, 2}, {0, 1}};
  for (size_t k = 0; k < spots.size(); ++k)
    rig.controllers.push_back(bump_controller("bump" + std::to_string(k), n, 1.5, spots[k], 0.15, 0.15, ranges[k]));
  Controller shear;
  shear.name = "shear";
  shear.offset = Positions::Zero(n.rows(), 3);
  for (Eigen::Index i = 0; i < n.rows(); ++i)
    shear.offset(i, 0) = 0.1 * std::max(0.0, n(i, 1)) * std::max(0.0, n(i, 2));
  rig.controllers.push_back(std::move(shear));
  part.millimetres_per_unit = 10;
  return part;
}

// tiny_bundle on fine_ball() with ball_rig() and the ball's still vertices (those no controller moves by more
// than 1e-4 units), as `retarget export` writes them from an avatar dataset.
inline std::string tiny_rig_bundle(const std::filesystem::path& folder) {
  RandomBundleOptions options = tiny_bundle_options();
  options.rig = ball_rig(fine_ball());
  const Rig& rig = options.rig->rig;
  for (int i = 0; i < rig.neutral.vertex_count(); ++i) {
    double motion = 0;
    for (const Controller& c : rig.controllers)
      motion = std::max(motion, c.offset.row(i).norm() * std::max(std::abs(c.min), std::abs(c.max)));
    if (motion <= 1e-4) options.avatar_still_vertices.push_back(i);
  }
  write_random_bundle(human_patch(), fine_ball(), folder.string(), options);
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

// The file's lines, without their line ends.
inline std::vector<std::string> lines_of(const std::filesystem::path& path) {
  std::istringstream in(read_text(path));
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

inline void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

#ifdef RETARGET_INFER_EXE
// The real retarget-infer with `arguments` (shell-quoted by the caller), its stdout and stderr
// in `log`; returns its exit status (-1 when it did not exit).
inline int run_infer_cli(const std::string& arguments, const std::filesystem::path& log) {
  const std::string command =
      std::string("'") + RETARGET_INFER_EXE + "' " + arguments + " >'" + log.string() + "' 2>&1";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}
#endif

}  // namespace retarget::test
