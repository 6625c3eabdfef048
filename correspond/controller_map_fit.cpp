#include "correspond/controller_map_fit.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/config.h"
#include "core/error.h"

namespace retarget {

void ControllerMapOptions::validate(const std::string& key_path) const {
  require(std::isfinite(prior_weight) && prior_weight >= 0, key_path + ".prior_weight",
          fmt::format("expected a number >= 0, got {}", prior_weight));
}

ControllerMap fit_controller_map(const std::vector<std::map<std::string, double>>& human,
                                 const Eigen::MatrixXd& controller_weights, const std::vector<std::string>& controllers,
                                 const std::vector<std::string>& shapes, const ControllerMap* prior,
                                 const ControllerMapOptions& options) {
  options.validate();
  const Eigen::Index k = static_cast<Eigen::Index>(human.size());
  const Eigen::Index c = static_cast<Eigen::Index>(controllers.size()), s = static_cast<Eigen::Index>(shapes.size());
  if (controller_weights.rows() != k || controller_weights.cols() != c)
    throw Error("controller map", fmt::format("{} human expressions and {} x {} controller weights for {} controllers",
                                              k, controller_weights.rows(), controller_weights.cols(), c));
  if (s == 0) throw Error("controller map", "no human shapes to map from");
  if (prior && (prior->controllers != controllers || prior->shapes != shapes))
    throw Error("controller map", "the prior names other controllers or shapes than the fit");
  Eigen::MatrixXd r = Eigen::MatrixXd::Zero(k, s);  // K x S recipe weights
  for (Eigen::Index i = 0; i < k; ++i)
    for (Eigen::Index j = 0; j < s; ++j) {
      const auto it = human[static_cast<size_t>(i)].find(shapes[static_cast<size_t>(j)]);
      if (it != human[static_cast<size_t>(i)].end()) r(i, j) = it->second;
    }
  // One normal matrix for every controller: (R^T R + l I) M^T = R^T Y + l P^T.
  const double lambda =
      std::max(1e-9, options.prior_weight * static_cast<double>(std::max<Eigen::Index>(k, 1)) / static_cast<double>(s));
  Eigen::MatrixXd normal = r.transpose() * r;
  normal.diagonal().array() += lambda;
  Eigen::MatrixXd rhs = r.transpose() * controller_weights;  // S x C
  if (prior) rhs += lambda * prior->matrix.transpose();
  ControllerMap map;
  map.controllers = controllers;
  map.shapes = shapes;
  map.matrix = normal.ldlt().solve(rhs).transpose();
  map.pairs = static_cast<int>(k);
  map.prior = prior ? prior->prior : "";
  return map;
}

void RankingOptions::validate(const std::string& key_path) const {
  require(std::isfinite(prior_weight) && prior_weight >= 0, key_path + ".prior_weight",
          fmt::format("expected a number >= 0, got {}", prior_weight));
  require(std::isfinite(champion_weight) && champion_weight >= 0, key_path + ".champion_weight",
          fmt::format("expected a number >= 0, got {}", champion_weight));
  require(steps >= 1, key_path + ".steps", fmt::format("expected at least 1, got {}", steps));
  require(std::isfinite(lr) && lr > 0, key_path + ".lr", fmt::format("expected a positive rate, got {}", lr));
}

namespace {

// Recipe weights as rows over `shapes`, [N, S] float64.
torch::Tensor shape_rows(const std::vector<const std::map<std::string, double>*>& rows,
                         const std::vector<std::string>& shapes) {
  torch::Tensor out =
      torch::zeros({static_cast<int64_t>(rows.size()), static_cast<int64_t>(shapes.size())}, torch::kFloat64);
  auto a = out.accessor<double, 2>();
  for (size_t i = 0; i < rows.size(); ++i)
    for (size_t j = 0; j < shapes.size(); ++j) {
      const auto it = rows[i]->find(shapes[j]);
      if (it != rows[i]->end()) a[static_cast<int64_t>(i)][static_cast<int64_t>(j)] = it->second;
    }
  return out;
}

torch::Tensor tensor_of(const Eigen::MatrixXd& m) {
  torch::Tensor t = torch::empty({m.rows(), m.cols()}, torch::kFloat64);
  auto a = t.accessor<double, 2>();
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) a[i][j] = m(i, j);
  return t;
}

}  // namespace

ControllerMap fit_controller_map_ranked(const std::vector<std::map<std::string, double>>& champions,
                                        const Eigen::MatrixXd& controller_weights,
                                        const std::vector<RankedPair>& comparisons, const Eigen::MatrixXd& metric,
                                        const std::vector<std::string>& controllers,
                                        const std::vector<std::string>& shapes, const ControllerMap& prior,
                                        const RankingOptions& options) {
  options.validate();
  const auto c = static_cast<Eigen::Index>(controllers.size());
  if (prior.controllers != controllers || prior.shapes != shapes)
    throw Error("controller map", "the prior names other controllers or shapes than the fit");
  if (controller_weights.rows() != static_cast<Eigen::Index>(champions.size()) ||
      (!champions.empty() && controller_weights.cols() != c))
    throw Error("controller map",
                fmt::format("{} champions and {} x {} controller weights for {} controllers", champions.size(),
                            controller_weights.rows(), controller_weights.cols(), c));
  if (metric.rows() != c || metric.cols() != c)
    throw Error("controller map", fmt::format("a {} x {} metric for {} controllers", metric.rows(), metric.cols(), c));
  for (const RankedPair& p : comparisons)
    if (p.positive.size() != c || p.negative.size() != c)
      throw Error("controller map", fmt::format("a comparison's weights are not {} controllers", c));

  torch::NoGradGuard outer;
  const torch::Tensor g = tensor_of(metric), p0 = tensor_of(prior.matrix);
  std::vector<const std::map<std::string, double>*> champion_rows, comparison_rows;
  for (const auto& r : champions) champion_rows.push_back(&r);
  Eigen::MatrixXd pos(static_cast<Eigen::Index>(comparisons.size()), c), neg(pos.rows(), c);
  for (size_t t = 0; t < comparisons.size(); ++t) {
    comparison_rows.push_back(&comparisons[t].human);
    pos.row(static_cast<Eigen::Index>(t)) = comparisons[t].positive.transpose();
    neg.row(static_cast<Eigen::Index>(t)) = comparisons[t].negative.transpose();
  }
  const torch::Tensor rc = shape_rows(champion_rows, shapes), yc = tensor_of(controller_weights);
  const torch::Tensor rt = shape_rows(comparison_rows, shapes), yp = tensor_of(pos), yn = tensor_of(neg);
  const auto squared = [&](const torch::Tensor& d) { return (d.matmul(g) * d).sum(1); };  // |d|^2_G per row
  const auto margins = [&](const torch::Tensor& m) {
    const torch::Tensor predicted = rt.matmul(m.t());
    return squared(predicted - yp) - squared(predicted - yn);  // < 0: the answer is kept
  };
  double tau = 1e-6;
  if (!comparisons.empty()) tau = std::max(tau, margins(p0).abs().median().item<double>());

  torch::Tensor m = p0.clone().requires_grad_(true);
  torch::optim::Adam adam({m}, torch::optim::AdamOptions(options.lr));
  const double s = static_cast<double>(std::max<size_t>(shapes.size(), 1));
  for (int step = 0; step < options.steps; ++step) {
    torch::AutoGradMode grad(true);
    adam.zero_grad();
    torch::Tensor loss = options.prior_weight * (m - p0).pow(2).sum() / s;
    if (!champions.empty() && options.champion_weight > 0)
      loss = loss + options.champion_weight * squared(rc.matmul(m.t()) - yc).mean();
    if (!comparisons.empty()) loss = loss + tau * torch::nn::functional::softplus(margins(m) / tau).mean();
    loss.backward();
    adam.step();
  }
  ControllerMap map;
  map.controllers = controllers;
  map.shapes = shapes;
  const torch::Tensor fitted = m.detach().contiguous();
  map.matrix = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      fitted.data_ptr<double>(), fitted.size(0), fitted.size(1));
  map.pairs = static_cast<int>(champions.size());
  map.prior = prior.prior;
  return map;
}

PriorWeightChoice choose_prior_weight(const std::vector<std::map<std::string, double>>& champions,
                                      const Eigen::MatrixXd& controller_weights,
                                      const std::vector<RankedPair>& comparisons, const Eigen::MatrixXd& metric,
                                      const std::vector<std::string>& controllers,
                                      const std::vector<std::string>& shapes, const ControllerMap& prior,
                                      const RankingOptions& options, const std::vector<double>& grid, int folds) {
  if (folds < 2) throw Error("controller map", fmt::format("cross-validation needs 2 folds or more, got {}", folds));
  // Each distinct recipe is one expression; expressions are dealt to the folds in turn.
  std::vector<std::map<std::string, double>> recipes;
  const auto fold_of = [&](const std::map<std::string, double>& r) {
    auto it = std::find(recipes.begin(), recipes.end(), r);
    if (it == recipes.end()) it = recipes.insert(recipes.end(), r);
    return static_cast<int>((it - recipes.begin()) % folds);
  };
  std::vector<int> champion_fold, comparison_fold;
  for (const auto& r : champions) champion_fold.push_back(fold_of(r));
  for (const RankedPair& p : comparisons) comparison_fold.push_back(fold_of(p.human));
  const auto agrees = [&](const ControllerMap& map, const RankedPair& p) {
    const Eigen::VectorXd y = map.apply(p.human);
    const Eigen::VectorXd a = y - p.positive, b = y - p.negative;
    return a.dot(metric * a) < b.dot(metric * b);
  };
  // Each fold's training set, built once for every weight.
  struct Fold {
    std::vector<std::map<std::string, double>> champions;
    Eigen::MatrixXd rows;  // their controller weights
    std::vector<RankedPair> comparisons;
  };
  std::vector<Fold> training(static_cast<size_t>(folds));
  for (int f = 0; f < folds; ++f) {
    Fold& fold = training[static_cast<size_t>(f)];
    std::vector<Eigen::Index> kept;
    for (size_t i = 0; i < champions.size(); ++i)
      if (champion_fold[i] != f) fold.champions.push_back(champions[i]), kept.push_back(static_cast<Eigen::Index>(i));
    fold.rows.resize(static_cast<Eigen::Index>(kept.size()), static_cast<Eigen::Index>(controllers.size()));
    for (size_t i = 0; i < kept.size(); ++i)
      fold.rows.row(static_cast<Eigen::Index>(i)) = controller_weights.row(kept[i]);
    for (size_t i = 0; i < comparisons.size(); ++i)
      if (comparison_fold[i] != f) fold.comparisons.push_back(comparisons[i]);
  }
  PriorWeightChoice choice;
  std::vector<double> candidates = grid;
  candidates.push_back(std::numeric_limits<double>::infinity());
  int held_out = 0;
  for (double weight : candidates) {
    int agree = 0, total = 0;
    for (int f = 0; f < folds; ++f) {
      const Fold& fold = training[static_cast<size_t>(f)];
      ControllerMap map = prior;
      if (std::isfinite(weight)) {
        RankingOptions o = options;
        o.prior_weight = weight;
        map = fit_controller_map_ranked(fold.champions, fold.rows, fold.comparisons, metric, controllers, shapes, prior,
                                        o);
      }
      for (size_t i = 0; i < comparisons.size(); ++i)
        if (comparison_fold[i] == f) agree += agrees(map, comparisons[i]), ++total;
    }
    const double fraction = total > 0 ? static_cast<double>(agree) / total : 0;
    choice.agreement.emplace_back(weight, fraction);
    held_out = total;
  }
  // The one-standard-error rule: the largest weight (the prior alone last) whose agreement is
  // within one standard error of the best's, so that a correction must beat the prior by more
  // than the comparisons' own noise to be taken.
  double best = 0;
  for (const auto& entry : choice.agreement) best = std::max(best, entry.second);
  const double error = held_out > 0 ? std::sqrt(best * (1 - best) / held_out) : 0;
  for (const auto& [weight, fraction] : choice.agreement)
    if (fraction >= best - error) choice.weight = weight;
  return choice;
}

}  // namespace retarget
