#include "eval/vae_evaluation.h"

#include <fmt/format.h>

#include <cmath>
#include <memory>
#include <optional>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/timer.h"
#include "data/still_vertices.h"
#include "geometry/expression_error.h"
#include "geometry/expression_sampling.h"
#include "geometry/metrics.h"
#include "geometry/part_motion.h"
#include "geometry/reconstruction.h"
#include "geometry/rig.h"
#include "geometry/rig_footprint.h"
#include "geometry/topology_fingerprint.h"

namespace retarget {

void VaeEvaluationOptions::validate() const {
  require(split == "test" || split == "train" || split == "all", "split",
          "expected 'test', 'train' or 'all', got '" + split + "'");
  require_positive(static_cast<double>(batch), "batch");
  require(target_normaliser == "targets" || target_normaliser == "shared", "target_normaliser",
          "expected 'targets' or 'shared', got '" + target_normaliser + "'");
}

namespace {

std::vector<int64_t> split_rows(const Dataset& d, const std::string& split) {
  if (split == "test") return d.test;
  if (split == "train") return d.train;
  std::vector<int64_t> all(static_cast<size_t>(d.sample_count()));
  for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int64_t>(i);
  return all;
}

// The rig of an avatar dataset, when it can still be read and has the dataset's topology.
std::optional<Rig> dataset_rig(const Dataset& d) {
  if (d.kind != DatasetKind::avatar || !d.weights.defined()) return std::nullopt;
  try {
    Rig rig = load_dataset_rig(d);
    if (static_cast<int64_t>(rig.controllers.size()) != d.weights.size(1)) {
      log::warn("{}: the rig no longer matches the dataset; comparing with meshes rebuilt from its features", d.source);
      return std::nullopt;
    }
    return rig;
  } catch (const Error& e) {
    log::warn("cannot read the dataset's rig ({}); comparing with meshes rebuilt from its features", e.what());
    return std::nullopt;
  }
}

double mean_pair_distance(const torch::Tensor& a, const torch::Tensor& b, bool same_set) {
  const torch::Tensor d = torch::cdist(a, b);
  if (!same_set) return d.mean().item<double>();
  const int64_t n = a.size(0);
  if (n < 2) return std::nan("");
  return d.sum().item<double>() / static_cast<double>(n * (n - 1));
}

// How far apart the codes [N, latent] of the split's rows lie within one expression (across
// subjects: one sample per subject and expression) and between expressions; fills
// within_expression, between_expression and their ratio.
void code_distances(const torch::Tensor& codes, const Dataset& d, const std::vector<int64_t>& rows,
                    VaeEvaluation& result) {
  const torch::Tensor z = codes.to(torch::kFloat64);
  const torch::Tensor expression = d.expression.index_select(0, torch::tensor(rows, torch::kInt64));
  std::vector<torch::Tensor> groups;
  for (int64_t e = 0; e < static_cast<int64_t>(d.expressions.size()); ++e) {
    const torch::Tensor members = (expression == e).nonzero().flatten();
    if (members.numel() > 0) groups.push_back(z.index_select(0, members));
  }
  double within = 0, between = 0;
  int within_n = 0, between_n = 0;
  for (size_t a = 0; a < groups.size(); ++a) {
    const double w = mean_pair_distance(groups[a], groups[a], true);
    if (std::isfinite(w)) {
      within += w;
      ++within_n;
    }
    for (size_t b = a + 1; b < groups.size(); ++b) {
      between += mean_pair_distance(groups[a], groups[b], false);
      ++between_n;
    }
  }
  if (within_n > 0 && between_n > 0) {
    result.within_expression = within / within_n;
    result.between_expression = between / between_n;
    result.code_distance_ratio = result.within_expression / result.between_expression;
  }
}

}  // namespace

const TrivialScore* VaeEvaluation::trivial_answer(const std::string& name) const {
  for (const TrivialScore& t : trivial)
    if (t.name == name) return &t;
  return nullptr;
}

VaeEvaluation evaluate_vae(MeshVaeImpl& vae, const Dataset& d, const VaeEvaluationOptions& options) {
  options.validate();
  Stopwatch clock;
  if (vae.options.vertices() != d.vertex_count())
    throw Error(d.folder, fmt::format("the VAE is for {} vertices, the dataset's mesh has {}", vae.options.vertices(),
                                      d.vertex_count()));
  const std::vector<int64_t> rows = split_rows(d, options.split);
  if (rows.empty()) throw Error(d.folder, "the " + options.split + " split is empty");
  const bool human = d.kind == DatasetKind::human;

  VaeEvaluation result;
  result.split = options.split;
  result.samples = static_cast<int64_t>(rows.size());
  result.vertices = d.vertex_count();
  if (!d.eyes.left.empty() && !d.eyes.right.empty()) {
    result.unit_scale = millimetres_per_unit(d.rest.vertices, d.eyes);
  } else {
    result.unit = "units";
    log::warn("{}: no eye landmarks, errors are in mesh units, not mm", d.folder);
  }
  const std::optional<Rig> rig = dataset_rig(d);
  result.ground_truth = human ? "identity-averaged targets (rebuilt from their features)"
                        : rig ? "rig meshes"
                              : "meshes rebuilt from the stored features";

  ReconstructionOptions reconstruction_options;
  reconstruction_options.weighting = d.dr.weighting;
  if (options.anchors) reconstruction_options.anchors = still_vertices(d);
  std::vector<int> part_vertices;  // every rigid part's vertices, ascending
  if (rig && !human) {
    std::vector<std::vector<int>> parts = rig_parts_to_move(*rig);
    for (const std::vector<int>& part : parts) part_vertices.insert(part_vertices.end(), part.begin(), part.end());
    std::sort(part_vertices.begin(), part_vertices.end());
    if (options.part_motion && !parts.empty())
      reconstruction_options.parts = std::make_shared<const PartMotion>(*rig, std::move(parts));
  }
  const Reconstruction reconstruction(d.rest, reconstruction_options);
  // What the decoder produces, normalised (train/vae_run.h decoder_normaliser).
  const Normaliser& out_normaliser =
      human && options.target_normaliser == "targets" ? d.target_normaliser : d.normaliser;
  const torch::Tensor all_targets = human ? d.targets : d.features;
  // Humans: every expression's identity-averaged target mesh, built once.
  std::vector<Positions> target_meshes;
  if (human) {
    const torch::Tensor t = d.targets.to(torch::kFloat32).contiguous();
    target_meshes = reconstruction.reconstruct_batch(t.data_ptr<float>(), static_cast<int>(t.size(0)));
  }
  // The ground-truth meshes of some rows of the split (see the header).
  auto truth_of = [&](const std::vector<int64_t>& batch_rows) {
    const torch::Tensor idx = torch::tensor(batch_rows, torch::kInt64);
    std::vector<Positions> truth;
    if (human) {
      const torch::Tensor expression = d.expression.index_select(0, idx);
      const auto e = expression.accessor<int64_t, 1>();
      for (int64_t i = 0; i < expression.size(0); ++i) truth.push_back(target_meshes[static_cast<size_t>(e[i])]);
    } else if (rig) {
      const torch::Tensor w = d.weights.index_select(0, idx).to(torch::kFloat64).contiguous();
      const Eigen::MatrixXd weights =
          Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
              w.data_ptr<double>(), w.size(0), w.size(1));
      truth = evaluate_samples(*rig, weights);
    } else {
      const torch::Tensor t = d.features.index_select(0, idx).to(torch::kFloat32).contiguous();
      truth = reconstruction.reconstruct_batch(t.data_ptr<float>(), static_cast<int>(batch_rows.size()));
    }
    return truth;
  };
  auto batches = [&](const auto& visit) {
    for (size_t begin = 0; begin < rows.size(); begin += static_cast<size_t>(options.batch)) {
      const size_t end = std::min(rows.size(), begin + static_cast<size_t>(options.batch));
      visit(std::vector<int64_t>(rows.begin() + static_cast<std::ptrdiff_t>(begin),
                                 rows.begin() + static_cast<std::ptrdiff_t>(end)));
    }
  };

  // Where expressions happen: 0.1 mm in mesh units.
  const double still = 0.1 / result.unit_scale;
  RigFootprint footprint;
  if (rig) {
    footprint = rig_footprint(*rig, still);
    result.footprint = "rig controllers";
  } else {
    if (human) {
      footprint.motion = vertex_motion(d.rest.vertices, target_meshes);
    } else {
      footprint.motion = Eigen::VectorXd::Zero(d.vertex_count());
      batches([&](const std::vector<int64_t>& batch_rows) {
        footprint.motion = footprint.motion.cwiseMax(vertex_motion(d.rest.vertices, truth_of(batch_rows)));
      });
    }
    footprint.moving = moving_vertices(footprint.motion, still);
    result.footprint = "ground-truth meshes";
  }
  result.moving_vertices = static_cast<int>(footprint.moving.size());
  if (!part_vertices.empty()) {
    footprint.regions["parts"] = part_vertices;
    // Named parts on their own too: "part eye_left", "part teeth", ...
    for (const RigPart& part : rig->parts)
      if (part.kind != PartKind::other && part.vertices.size() >= 3)
        footprint.regions["part " + part.name] = part.vertices;
  }

  // The trivial answers: their meshes and normalised features ([V, 9] float32).
  const torch::Tensor neutral_features =
      out_normaliser.normalise(torch::zeros({d.vertex_count(), 9}, torch::kFloat32)).to(torch::kFloat32);
  torch::Tensor mean_features;
  Positions mean_mesh;
  if (human) {
    // The mean over the training split's samples of their targets: each expression's target
    // weighted by how many training samples show it.
    const torch::Tensor train_rows =
        d.train.empty() ? torch::arange(d.sample_count(), torch::kInt64) : torch::tensor(d.train, torch::kInt64);
    const torch::Tensor counts =
        torch::bincount(d.expression.index_select(0, train_rows), {}, d.targets.size(0)).to(torch::kFloat64);
    const torch::Tensor mean_raw = torch::tensordot(counts / counts.sum(), d.targets.to(torch::kFloat64), {0}, {0})
                                       .to(torch::kFloat32)
                                       .contiguous();
    mean_mesh = reconstruction.reconstruct(mean_raw.data_ptr<float>());
    mean_features = out_normaliser.normalise(mean_raw).to(torch::kFloat32);
  }

  torch::NoGradGuard no_grad;
  vae.eval();
  std::vector<torch::Tensor> codes;
  ExpressionErrorSum vae_sum, neutral_sum, mean_sum;
  double l1_sum = 0, neutral_l1_sum = 0, mean_l1_sum = 0;
  int64_t l1_count = 0;
  batches([&](const std::vector<int64_t>& batch_rows) {
    const torch::Tensor idx = torch::tensor(batch_rows, torch::kInt64);
    const torch::Tensor target_idx = human ? d.expression.index_select(0, idx) : idx;
    const torch::Tensor x = d.normaliser.normalise(d.features.index_select(0, idx)).to(torch::kFloat32);
    const torch::Tensor y = out_normaliser.normalise(all_targets.index_select(0, target_idx)).to(torch::kFloat32);
    const VaeOutput out = vae.forward(x, false);
    codes.push_back(out.mean);
    l1_sum += (out.reconstruction - y).abs().sum().item<double>();
    neutral_l1_sum += (y - neutral_features).abs().sum().item<double>();
    if (human) mean_l1_sum += (y - mean_features).abs().sum().item<double>();
    l1_count += y.numel();
    const torch::Tensor predicted = out_normaliser.denormalise(out.reconstruction).to(torch::kFloat32).contiguous();
    const std::vector<Positions> meshes =
        reconstruction.reconstruct_batch(predicted.data_ptr<float>(), static_cast<int>(batch_rows.size()));
    const std::vector<Positions> truth = truth_of(batch_rows);
    for (size_t i = 0; i < batch_rows.size(); ++i) {
      const ExpressionError e = expression_error(meshes[i], truth[i], result.unit_scale, footprint);
      vae_sum.add(e);
      if (e.max > result.max) {
        result.max = e.max;
        result.worst_sample = batch_rows[i];
        result.worst_vertex = e.worst_vertex;
      }
      neutral_sum.add(expression_error(d.rest.vertices, truth[i], result.unit_scale, footprint));
      if (human) mean_sum.add(expression_error(mean_mesh, truth[i], result.unit_scale, footprint));
    }
  });
  const ExpressionErrorSum vae_avg = vae_sum.averaged();
  result.mean = vae_avg.mean;
  result.mean_of_max = vae_avg.mean_of_max;
  result.moving_mean = vae_avg.moving_mean;
  result.region_mean = vae_avg.region_mean;
  result.feature_l1 = l1_sum / static_cast<double>(l1_count);

  auto trivial = [&](const std::string& name, const ExpressionErrorSum& sum, double l1) {
    const ExpressionErrorSum a = sum.averaged();
    TrivialScore t;
    t.name = name;
    t.mean = a.mean;
    t.mean_of_max = a.mean_of_max;
    t.max = a.max;
    t.moving_mean = a.moving_mean;
    t.region_mean = a.region_mean;
    t.feature_l1 = l1 / static_cast<double>(l1_count);
    return t;
  };
  result.trivial.push_back(trivial("neutral", neutral_sum, neutral_l1_sum));
  if (human) result.trivial.push_back(trivial("mean_expression", mean_sum, mean_l1_sum));
  const TrivialScore& neutral = result.trivial.front();
  if (neutral.mean > 0) result.fraction_of_neutral = result.mean / neutral.mean;
  if (neutral.moving_mean > 0) result.moving_fraction_of_neutral = result.moving_mean / neutral.moving_mean;

  if (human) code_distances(torch::cat(codes), d, rows, result);
  result.seconds = clock.seconds();
  return result;
}

}  // namespace retarget
