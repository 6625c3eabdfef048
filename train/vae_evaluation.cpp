#include "train/vae_evaluation.h"

#include <fmt/format.h>

#include <cmath>
#include <map>
#include <memory>
#include <optional>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/timer.h"
#include "geometry/expression_sampling.h"
#include "geometry/metrics.h"
#include "geometry/reconstruction.h"
#include "geometry/rig.h"
#include "geometry/rigid_alignment.h"
#include "geometry/topology_fingerprint.h"

namespace retarget {

void VaeEvaluationOptions::validate() const {
  require(split == "test" || split == "train" || split == "all", "split",
          "expected 'test', 'train' or 'all', got '" + split + "'");
  require_positive(static_cast<double>(batch), "batch");
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
    Rig rig = load_rig(d.source);
    if (topology_fingerprint(rig.neutral) != d.fingerprint ||
        static_cast<int64_t>(rig.controllers.size()) != d.weights.size(1)) {
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

}  // namespace

VaeEvaluation evaluate_vae(MeshVaeImpl& vae, const Dataset& d, const VaeEvaluationOptions& options) {
  options.validate();
  Stopwatch clock;
  if (vae.options.vertices() != d.vertex_count())
    throw Error(d.folder, fmt::format("the VAE is for {} vertices, the dataset's mesh has {}", vae.options.vertices(),
                                      d.vertex_count()));
  const std::vector<int64_t> rows = split_rows(d, options.split);
  if (rows.empty()) throw Error(d.folder, "the " + options.split + " split is empty");

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
  result.ground_truth = d.kind == DatasetKind::human ? "identity-averaged targets (rebuilt from their features)"
                        : rig                        ? "rig meshes"
                                                     : "meshes rebuilt from the stored features";

  const Reconstruction reconstruction(d.rest);
  const torch::Tensor all_targets = d.kind == DatasetKind::human ? d.targets : d.features;
  std::map<int64_t, Positions> target_meshes;  // humans: per expression, built once
  torch::NoGradGuard no_grad;
  vae.eval();
  std::vector<torch::Tensor> codes;
  double error_sum = 0, max_sum = 0, l1_sum = 0;
  int64_t l1_count = 0;
  for (size_t begin = 0; begin < rows.size(); begin += static_cast<size_t>(options.batch)) {
    const size_t end = std::min(rows.size(), begin + static_cast<size_t>(options.batch));
    const std::vector<int64_t> batch_rows(rows.begin() + static_cast<std::ptrdiff_t>(begin),
                                          rows.begin() + static_cast<std::ptrdiff_t>(end));
    const torch::Tensor idx = torch::tensor(batch_rows, torch::kInt64);
    const torch::Tensor target_idx = d.kind == DatasetKind::human ? d.expression.index_select(0, idx) : idx;
    const torch::Tensor x = d.normaliser.normalise(d.features.index_select(0, idx)).to(torch::kFloat32);
    const torch::Tensor y = d.normaliser.normalise(all_targets.index_select(0, target_idx)).to(torch::kFloat32);
    const VaeOutput out = vae.forward(x, false);
    codes.push_back(out.mean);
    l1_sum += (out.reconstruction - y).abs().sum().item<double>();
    l1_count += y.numel();
    const torch::Tensor predicted = d.normaliser.denormalise(out.reconstruction).to(torch::kFloat32).contiguous();
    const std::vector<Positions> meshes =
        reconstruction.reconstruct_batch(predicted.data_ptr<float>(), static_cast<int>(batch_rows.size()));

    std::vector<Positions> truth;
    if (d.kind == DatasetKind::human) {
      const auto expression = target_idx.accessor<int64_t, 1>();
      for (size_t i = 0; i < batch_rows.size(); ++i) {
        const int64_t e = expression[static_cast<int64_t>(i)];
        auto it = target_meshes.find(e);
        if (it == target_meshes.end()) {
          const torch::Tensor t = d.targets[e].to(torch::kFloat32).contiguous();
          it = target_meshes.emplace(e, reconstruction.reconstruct(t.data_ptr<float>())).first;
        }
        truth.push_back(it->second);
      }
    } else if (rig) {
      const torch::Tensor w = d.weights.index_select(0, idx).to(torch::kFloat64).contiguous();
      Eigen::MatrixXd weights(w.size(0), w.size(1));
      for (int64_t i = 0; i < w.size(0); ++i)
        for (int64_t j = 0; j < w.size(1); ++j) weights(i, j) = w[i][j].item<double>();
      truth = evaluate_samples(*rig, weights);
    } else {
      const torch::Tensor t = d.features.index_select(0, idx).to(torch::kFloat32).contiguous();
      truth = reconstruction.reconstruct_batch(t.data_ptr<float>(), static_cast<int>(batch_rows.size()));
    }
    for (size_t i = 0; i < batch_rows.size(); ++i) {
      const Positions aligned = rigid_alignment(meshes[i], truth[i]).apply(meshes[i]);
      const VertexError e = vertex_error(aligned, truth[i], result.unit_scale);
      error_sum += e.mean;
      max_sum += e.max;
      if (e.max > result.max) {
        result.max = e.max;
        result.worst_sample = batch_rows[i];
        result.worst_vertex = e.worst_vertex;
      }
    }
  }
  result.mean = error_sum / static_cast<double>(rows.size());
  result.mean_of_max = max_sum / static_cast<double>(rows.size());
  result.feature_l1 = l1_sum / static_cast<double>(l1_count);

  if (d.kind == DatasetKind::human) {
    // Codes grouped by expression; subjects differ within a group (one sample per subject
    // and expression).
    const torch::Tensor z = torch::cat(codes).to(torch::kFloat64);
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
  result.seconds = clock.seconds();
  return result;
}

}  // namespace retarget
