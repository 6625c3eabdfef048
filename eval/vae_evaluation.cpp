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

namespace {

// The split's rows, their ground truth (see the header) and how meshes are rebuilt from features.
struct EvalData {
  const Dataset& d;
  const VaeEvaluationOptions& options;
  const std::vector<int64_t>& rows;
  const bool human;
  const std::optional<Rig>& rig;
  const Reconstruction& reconstruction;
  std::vector<Positions> target_meshes;  // humans: every expression's identity-averaged target mesh

  // The ground-truth meshes of some rows of the split.
  std::vector<Positions> truth_of(const std::vector<int64_t>& batch_rows) const {
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
  }

  // visit(rows of one batch) for the split's batches in order.
  template <class Visit>
  void batches(const Visit& visit) const {
    for (size_t begin = 0; begin < rows.size(); begin += static_cast<size_t>(options.batch)) {
      const size_t end = std::min(rows.size(), begin + static_cast<size_t>(options.batch));
      visit(std::vector<int64_t>(rows.begin() + static_cast<std::ptrdiff_t>(begin),
                                 rows.begin() + static_cast<std::ptrdiff_t>(end)));
    }
  }
};

// The evaluation's description: split, sizes, units.
VaeEvaluation described(const Dataset& d, const VaeEvaluationOptions& options, size_t rows) {
  VaeEvaluation result;
  result.split = options.split;
  result.samples = static_cast<int64_t>(rows);
  result.vertices = d.vertex_count();
  if (!d.eyes.left.empty() && !d.eyes.right.empty()) {
    result.unit_scale = millimetres_per_unit(d.rest.vertices, d.eyes);
  } else {
    result.unit = "units";
    log::warn("{}: no eye landmarks, errors are in mesh units, not mm", d.folder);
  }
  return result;
}

// Where expressions happen (moving: 0.1 mm in mesh units), with the rig's parts as regions.
RigFootprint footprint_of(const EvalData& data, const std::vector<int>& part_vertices, VaeEvaluation& result) {
  const Dataset& d = data.d;
  const double still = 0.1 / result.unit_scale;
  RigFootprint footprint;
  if (data.rig) {
    footprint = rig_footprint(*data.rig, still);
    result.footprint = "rig controllers";
  } else {
    if (data.human) {
      footprint.motion = vertex_motion(d.rest.vertices, data.target_meshes);
    } else {
      footprint.motion = Eigen::VectorXd::Zero(d.vertex_count());
      data.batches([&](const std::vector<int64_t>& batch_rows) {
        footprint.motion = footprint.motion.cwiseMax(vertex_motion(d.rest.vertices, data.truth_of(batch_rows)));
      });
    }
    footprint.moving = moving_vertices(footprint.motion, still);
    result.footprint = "ground-truth meshes";
  }
  result.moving_vertices = static_cast<int>(footprint.moving.size());
  if (!part_vertices.empty()) {
    footprint.regions["parts"] = part_vertices;
    // Named parts on their own too: "part eye_left", "part teeth", ...
    for (const RigPart& part : data.rig->parts)
      if (part.kind != PartKind::other && part.vertices.size() >= 3)
        footprint.regions["part " + part.name] = part.vertices;
  }
  return footprint;
}

// The trivial answers: their meshes and normalised features ([V, 9] float32).
struct TrivialAnswers {
  torch::Tensor neutral_features;
  torch::Tensor mean_features;  // humans only
  Positions mean_mesh;          // humans only
};

TrivialAnswers trivial_answers(const EvalData& data, const Normaliser& out_normaliser) {
  const Dataset& d = data.d;
  TrivialAnswers out;
  out.neutral_features =
      out_normaliser.normalise(torch::zeros({d.vertex_count(), 9}, torch::kFloat32)).to(torch::kFloat32);
  if (!data.human) return out;
  // The mean over the training split's samples of their targets: each expression's target
  // weighted by how many training samples show it.
  const torch::Tensor train_rows =
      d.train.empty() ? torch::arange(d.sample_count(), torch::kInt64) : torch::tensor(d.train, torch::kInt64);
  const torch::Tensor counts =
      torch::bincount(d.expression.index_select(0, train_rows), {}, d.targets.size(0)).to(torch::kFloat64);
  const torch::Tensor mean_raw =
      torch::tensordot(counts / counts.sum(), d.targets.to(torch::kFloat64), {0}, {0}).to(torch::kFloat32).contiguous();
  out.mean_mesh = data.reconstruction.reconstruct(mean_raw.data_ptr<float>());
  out.mean_features = out_normaliser.normalise(mean_raw).to(torch::kFloat32);
  return out;
}

// The VAE's and the trivial answers' errors summed over the split.
struct ErrorSums {
  ExpressionErrorSum vae, neutral, mean;
  double l1 = 0, neutral_l1 = 0, mean_l1 = 0;  // feature L1, summed over entries
  int64_t l1_count = 0;
  std::vector<torch::Tensor> codes;  // per batch: the encoder's means
};

// (Called without gradients.)
ErrorSums score_batches(MeshVaeImpl& vae, const EvalData& data, const Normaliser& out_normaliser,
                        const TrivialAnswers& trivial, const RigFootprint& footprint, VaeEvaluation& result) {
  const Dataset& d = data.d;
  const bool human = data.human;
  const torch::Tensor all_targets = human ? d.targets : d.features;
  vae.eval();
  ErrorSums s;
  data.batches([&](const std::vector<int64_t>& batch_rows) {
    const torch::Tensor idx = torch::tensor(batch_rows, torch::kInt64);
    const torch::Tensor target_idx = human ? d.expression.index_select(0, idx) : idx;
    const torch::Tensor x = d.normaliser.normalise(d.features.index_select(0, idx)).to(torch::kFloat32);
    const torch::Tensor y = out_normaliser.normalise(all_targets.index_select(0, target_idx)).to(torch::kFloat32);
    const VaeOutput out = vae.forward(x, false);
    s.codes.push_back(out.mean);
    s.l1 += (out.reconstruction - y).abs().sum().item<double>();
    s.neutral_l1 += (y - trivial.neutral_features).abs().sum().item<double>();
    if (human) s.mean_l1 += (y - trivial.mean_features).abs().sum().item<double>();
    s.l1_count += y.numel();
    const torch::Tensor predicted = out_normaliser.denormalise(out.reconstruction).to(torch::kFloat32).contiguous();
    const std::vector<Positions> meshes =
        data.reconstruction.reconstruct_batch(predicted.data_ptr<float>(), static_cast<int>(batch_rows.size()));
    const std::vector<Positions> truth = data.truth_of(batch_rows);
    for (size_t i = 0; i < batch_rows.size(); ++i) {
      const ExpressionError e = expression_error(meshes[i], truth[i], result.unit_scale, footprint);
      s.vae.add(e);
      if (e.max > result.max) {
        result.max = e.max;
        result.worst_sample = batch_rows[i];
        result.worst_vertex = e.worst_vertex;
      }
      s.neutral.add(expression_error(d.rest.vertices, truth[i], result.unit_scale, footprint));
      if (human) s.mean.add(expression_error(trivial.mean_mesh, truth[i], result.unit_scale, footprint));
    }
  });
  return s;
}

TrivialScore trivial_score(const std::string& name, const ExpressionErrorSum& sum, double l1, int64_t l1_count) {
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
}

// The averages of `s` into `result`, and the VAE's errors as fractions of the neutral's.
void write_scores(const ErrorSums& s, bool human, VaeEvaluation& result) {
  const ExpressionErrorSum vae_avg = s.vae.averaged();
  result.mean = vae_avg.mean;
  result.mean_of_max = vae_avg.mean_of_max;
  result.moving_mean = vae_avg.moving_mean;
  result.region_mean = vae_avg.region_mean;
  result.feature_l1 = s.l1 / static_cast<double>(s.l1_count);
  result.trivial.push_back(trivial_score("neutral", s.neutral, s.neutral_l1, s.l1_count));
  if (human) result.trivial.push_back(trivial_score("mean_expression", s.mean, s.mean_l1, s.l1_count));
  const TrivialScore& neutral = result.trivial.front();
  if (neutral.mean > 0) result.fraction_of_neutral = result.mean / neutral.mean;
  if (neutral.moving_mean > 0) result.moving_fraction_of_neutral = result.moving_mean / neutral.moving_mean;
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
  const bool human = d.kind == DatasetKind::human;
  VaeEvaluation result = described(d, options, rows.size());
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
  EvalData data{d, options, rows, human, rig, reconstruction, {}};
  if (human) {
    const torch::Tensor t = d.targets.to(torch::kFloat32).contiguous();
    data.target_meshes = reconstruction.reconstruct_batch(t.data_ptr<float>(), static_cast<int>(t.size(0)));
  }
  // What the decoder produces, normalised (train/vae_run.h decoder_normaliser).
  const Normaliser& out_normaliser =
      human && options.target_normaliser == "targets" ? d.target_normaliser : d.normaliser;

  const RigFootprint footprint = footprint_of(data, part_vertices, result);
  const TrivialAnswers trivial = trivial_answers(data, out_normaliser);
  torch::NoGradGuard no_grad;
  const ErrorSums sums = score_batches(vae, data, out_normaliser, trivial, footprint, result);
  write_scores(sums, human, result);
  if (human) code_distances(torch::cat(sums.codes), d, rows, result);
  result.seconds = clock.seconds();
  return result;
}

}  // namespace retarget
