#include "bench/infer_benchmark.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include "core/config.h"
#include "core/error.h"
#include "export/bundle_export.h"
#include "geometry/mesh_io.h"
#include "geometry/primitive_meshes.h"
#include "geometry/synthetic_deformations.h"
#include "models/graph_operator.h"

namespace retarget {

namespace {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;

BundleSide random_side(const Mesh& rest, const std::string& name, const RandomBundleOptions& options) {
  BundleSide side;
  const int64_t v = rest.vertex_count();
  side.vae = MeshVae(mesh_graph_operator(rest), MeshVaeOptions(v)
                                                    .channels(options.channels)
                                                    .hidden(options.hidden)
                                                    .latent(options.latent)
                                                    .order(options.order)
                                                    .encoder_skip(options.encoder_skip));
  side.vae->eval();
  side.normaliser_min = -options.range * (1 + 0.1 * torch::rand({v, 9}));
  side.normaliser_max = options.range * (1 + 0.1 * torch::rand({v, 9}));
  side.rest = rest;
  side.name = name;
  return side;
}

}  // namespace

void RandomBundleOptions::validate() const {
  require(!channels.empty() && channels.front() == 9, "random_bundle.channels",
          "expected the DR feature width 9 first");
  require_positive(static_cast<double>(hidden), "random_bundle.hidden");
  require_positive(static_cast<double>(latent), "random_bundle.latent");
  require_positive(static_cast<double>(translation_hidden), "random_bundle.translation_hidden");
  require_positive(range, "random_bundle.range");
}

void write_random_bundle(const Mesh& human_rest, const Mesh& avatar_rest, const std::string& folder,
                         const RandomBundleOptions& options) {
  options.validate();
  torch::manual_seed(options.seed);
  BundleParts parts;
  parts.human = random_side(human_rest, options.human_name, options);
  parts.avatar = random_side(avatar_rest, options.avatar_name, options);
  parts.avatar.units = options.avatar_units;
  parts.avatar.still_vertices = options.avatar_still_vertices;
  parts.rig = options.rig;
  parts.translation = TranslationMlp(
      TranslationMlpOptions().latent_in(options.latent).hidden(options.translation_hidden).latent_out(options.latent));
  export_bundle(parts, folder);
}

std::vector<Positions> deformed_frames(const Mesh& rest, int count) {
  const Positions& V = rest.vertices;
  const Eigen::RowVector3d lo = V.colwise().minCoeff(), hi = V.colwise().maxCoeff();
  const Eigen::Vector3d centre = (0.5 * (lo + hi)).transpose();
  const double diagonal = (hi - lo).norm();
  std::vector<Positions> frames;
  frames.reserve(count);
  for (int k = 0; k < count; ++k) {
    const double phase = 2 * kPi * k / std::max(count, 1);
    const Eigen::Vector3d spot = centre + 0.35 * diagonal * Eigen::Vector3d(std::cos(phase), 0.3, std::sin(phase));
    Positions p = bulge(V, spot, 0.2 * diagonal, Eigen::Vector3d::UnitZ(), 0.03 * diagonal * std::sin(3 * phase));
    p = twist(p, Eigen::Vector3d::UnitY(), centre, 15.0 * std::sin(phase), lo.y() + 0.3 * (hi.y() - lo.y()),
              lo.y() + 0.8 * (hi.y() - lo.y()));
    frames.push_back(std::move(p));
  }
  return frames;
}

InferOptions prepare_inference_benchmark(const InferBenchmarkOptions& options) {
  if (options.folder.empty()) throw Error("infer_benchmark.folder", "give a scratch folder");
  const fs::path dir(options.folder);
  fs::remove_all(dir);
  const Mesh human = uv_sphere(options.human_rings, options.human_segments);
  const Mesh avatar = uv_sphere(options.avatar_rings, options.avatar_segments);
  write_random_bundle(human, avatar, (dir / "bundle").string(), options.bundle);
  const std::vector<Positions> frames = deformed_frames(human, options.frames);
  for (int k = 0; k < options.frames; ++k) {
    write_mesh((dir / "input" / ("frame_" + std::to_string(k + 1) + ".obj")).string(),
               with_positions(human, frames[k]));
  }
  InferOptions run = options.run;
  run.bundle = (dir / "bundle").string();
  run.inputs = {(dir / "input").string()};
  run.out = (dir / "output").string();
  return run;
}

InferSummary run_inference_benchmark(const InferBenchmarkOptions& options) {
  return run_inference(prepare_inference_benchmark(options));
}

}  // namespace retarget
