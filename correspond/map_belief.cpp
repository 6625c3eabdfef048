#include "correspond/map_belief.h"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/log.h"
#include "geometry/gaussian_box_mode.h"

namespace retarget {

namespace {

// The shapes a recipe uses: c = sum over them of r_s M[:, s], so only their blocks of the
// belief matter (a recipe uses a few of the face model's shapes).
std::vector<Eigen::Index> used_shapes(const Eigen::VectorXd& recipe) {
  std::vector<Eigen::Index> used;
  for (Eigen::Index s = 0; s < recipe.size(); ++s)
    if (recipe(s) != 0) used.push_back(s);
  return used;
}

// Each entry's move no further than in any of `withouts` (the moves with one annotator left
// out), and none where one of them turns it back.
Eigen::VectorXd smallest_move(Eigen::VectorXd move, const std::vector<Eigen::VectorXd>& withouts) {
  for (const Eigen::VectorXd& without : withouts)
    for (Eigen::Index i = 0; i < move.size(); ++i)
      move(i) = without(i) * move(i) <= 0 ? 0.0 : std::abs(without(i)) < std::abs(move(i)) ? without(i) : move(i);
  return move;
}

// Each entry's move m times max(0, 1 - z^2 V / m^2), V its jackknife variance over `withouts`
// ((n - 1) / n times the sum of squared deviations from their mean). Fewer than two: unchanged.
Eigen::VectorXd jackknifed_move(Eigen::VectorXd move, const std::vector<Eigen::VectorXd>& withouts, double z) {
  const auto n = static_cast<double>(withouts.size());
  if (withouts.size() < 2) return move;
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(move.size()), spread = Eigen::VectorXd::Zero(move.size());
  for (const Eigen::VectorXd& without : withouts) mean += without / n;
  for (const Eigen::VectorXd& without : withouts) spread += (without - mean).cwiseAbs2();
  for (Eigen::Index i = 0; i < move.size(); ++i) {
    const double variance = (n - 1) / n * spread(i), m2 = move(i) * move(i);
    move(i) = m2 > 0 ? move(i) * std::max(0.0, 1 - z * z * variance / m2) : 0.0;
  }
  return move;
}

}  // namespace

MapBelief::MapBelief(const ControllerMap& prior, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                     const BeliefSearchOptions& options)
    : prior_(prior), lower_(lower), upper_(upper), options_(options) {
  options.validate();
  const Eigen::Index c = prior.matrix.rows(), s = prior.matrix.cols();
  if (lower.size() != c || upper.size() != c)
    throw Error("correspond.belief",
                fmt::format("a map of {} controllers but ranges for {} and {}", c, lower.size(), upper.size()));
  if (((upper - lower).array() <= 0).any()) throw Error("correspond.belief", "a controller has an empty range");
  mean_ = Eigen::Map<const Eigen::VectorXd>(prior.matrix.data(), c * s);  // column-major: s * C + c
  const Eigen::VectorXd sd = options.prior_sd * (upper - lower);
  prior_variance_ = sd.array().square().replicate(s, 1);
  // A controller the prior reads as some shapes is surer not to listen to the others; an empty
  // row (no counterpart found) says nothing either way.
  const double off = options.off_table * options.off_table;
  for (Eigen::Index row = 0; row < c; ++row)
    if ((prior.matrix.row(row).array() != 0).any())
      for (Eigen::Index shape = 0; shape < s; ++shape)
        if (prior.matrix(row, shape) == 0) prior_variance_(shape * c + row) *= off;
  covariance_ = prior_variance_.asDiagonal();
}

Eigen::VectorXd MapBelief::recipe_vector(const std::map<std::string, double>& weights) const {
  Eigen::VectorXd r = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(prior_.shapes.size()));
  for (size_t s = 0; s < prior_.shapes.size(); ++s) {
    const auto it = weights.find(prior_.shapes[s]);
    if (it != weights.end()) r(static_cast<Eigen::Index>(s)) = it->second;
  }
  return r;
}

std::vector<std::string> MapBelief::unreached_controllers(double kept) const {
  if (!(kept > 0 && kept <= 1)) throw Error("correspond.belief", fmt::format("kept: expected (0, 1], got {}", kept));
  const Eigen::Index c = prior_.matrix.rows(), s = prior_.matrix.cols();
  std::vector<bool> used(static_cast<size_t>(s), false);
  for (const Site& site : sites_)
    for (const Eigen::Index shape : used_shapes(site.recipe)) used[static_cast<size_t>(shape)] = true;
  std::vector<std::string> unreached;
  for (Eigen::Index row = 0; row < c; ++row) {
    bool observed = false, reached = false;
    for (Eigen::Index shape = 0; shape < s && !reached; ++shape) {
      if (!used[static_cast<size_t>(shape)]) continue;
      const Eigen::Index d = shape * c + row;
      observed = true;
      reached = covariance_(d, d) < kept * kept * prior_variance_(d);
    }
    if (observed && !reached) unreached.push_back(prior_.controllers[static_cast<size_t>(row)]);
  }
  return unreached;
}

Belief MapBelief::expression(const Eigen::VectorXd& recipe) const {
  const Eigen::Index c = prior_.matrix.rows();
  if (recipe.size() != prior_.matrix.cols())
    throw Error("correspond.belief",
                fmt::format("a recipe of {} weights for a map of {} shapes", recipe.size(), prior_.matrix.cols()));
  Belief b{Eigen::VectorXd::Zero(c), Eigen::MatrixXd::Zero(c, c)};
  const std::vector<Eigen::Index> used = used_shapes(recipe);
  for (const Eigen::Index s : used) {
    b.mean += recipe(s) * mean_.segment(s * c, c);
    for (const Eigen::Index t : used) b.covariance += recipe(s) * recipe(t) * covariance_.block(s * c, t * c, c, c);
  }
  return b;
}

MapBelief::Site MapBelief::read_answer(const Eigen::VectorXd& recipe, const Eigen::MatrixXd& metric,
                                       const Eigen::VectorXd& positive, const Eigen::VectorXd& negative,
                                       const std::string& annotator) {
  Site site{recipe, positive, negative, Eigen::VectorXd(), metric, 0, 0, annotator};
  const CutUpdate u = comparison_update(expression(recipe), metric, positive, negative, lower_, upper_, options_);
  if (u.n.size() == 0 || !std::isfinite(u.gain) || !std::isfinite(u.curvature)) return site;
  // N = r (x) n, the cut's direction in map space (only the used shapes' blocks), and Sigma N.
  const Eigen::Index c = prior_.matrix.rows();
  site.direction = Eigen::VectorXd::Zero(mean_.size());
  for (const Eigen::Index s : used_shapes(recipe)) site.direction.segment(s * c, c) = recipe(s) * u.n;
  const Eigen::VectorXd sigma_n = covariance_ * site.direction;
  // Along N the belief's variance v and mean mu become v + v^2 curvature and mu + v gain; the
  // factor is what turns the one into the other (in natural parameters).
  const double v = site.direction.dot(sigma_n), mu = site.direction.dot(mean_);
  const double v_new = v + v * v * u.curvature, mu_new = mu + v * u.gain;
  if (v > 0 && v_new > 0) {
    site.tau = 1 / v_new - 1 / v;
    site.nu = mu_new / v_new - mu / v;
  }
  mean_ += sigma_n * u.gain;
  covariance_.noalias() += sigma_n * sigma_n.transpose() * u.curvature;
  return site;
}

void MapBelief::observe(const Eigen::VectorXd& recipe, const Eigen::MatrixXd& metric, const Eigen::VectorXd& positive,
                        const Eigen::VectorXd& negative, const std::string& annotator) {
  sites_.push_back(read_answer(recipe, metric, positive, negative, annotator));
  ++observed_;
}

void MapBelief::shift_projection(const Eigen::VectorXd& sigma_n, double v, double mu, double v_to, double mu_to) {
  mean_ += sigma_n * ((mu_to - mu) / v);
  covariance_.noalias() += sigma_n * sigma_n.transpose() * ((v_to - v) / (v * v));
}

void MapBelief::refine(int passes) {
  if (passes <= 0) return;
  for (int pass = 0; pass < passes; ++pass)
    for (Site& site : sites_) {
      if (site.direction.size() == 0) continue;
      // The cavity: the belief without this answer's factor.
      const Eigen::VectorXd sigma_n = covariance_ * site.direction;
      const double v = site.direction.dot(sigma_n), mu = site.direction.dot(mean_);
      const double precision = 1 / v - site.tau;
      if (!(v > 0) || !(precision > 0)) continue;  // no proper cavity: keep the factor
      const double v_cavity = 1 / precision, mu_cavity = v_cavity * (mu / v - site.nu);
      shift_projection(sigma_n, v, mu, v_cavity, mu_cavity);
      Site again = read_answer(site.recipe, site.metric, site.positive, site.negative, site.annotator);
      if (again.direction.size() == 0) {  // read as teaching nothing now: the old factor back
        shift_projection(sigma_n * (v_cavity / v), v_cavity, mu_cavity, v, mu);  // Sigma_cavity N = Sigma N v_c / v
        continue;
      }
      site = std::move(again);
    }
  covariance_ = 0.5 * (covariance_ + covariance_.transpose());
}

std::array<Eigen::VectorXd, 2> MapBelief::next_pair(const Eigen::VectorXd& recipe,
                                                    const Eigen::MatrixXd& metric) const {
  return most_informative_pair(expression(recipe), metric, lower_, upper_, options_);
}

ControllerMap MapBelief::likely_map() const {
  ControllerMap m = prior_;
  const Eigen::Index c = prior_.matrix.rows(), s = prior_.matrix.cols();
  const Eigen::VectorXd lo = lower_.cwiseMin(0.0).replicate(s, 1), hi = upper_.cwiseMax(0.0).replicate(s, 1);
  const Eigen::VectorXd prior = Eigen::Map<const Eigen::VectorXd>(prior_.matrix.data(), c * s);
  const Eigen::VectorXd pull = (options_.sparsity / (upper_ - lower_).array()).matrix().replicate(s, 1);
  const Eigen::VectorXd start = prior.cwiseMax(lo).cwiseMin(hi);
  const auto mode_of = [&](const Eigen::VectorXd& mean, const Eigen::MatrixXd& covariance) {
    return sparse_box_mode(mean, covariance, start, pull, lo, hi);
  };
  Eigen::VectorXd mean = mean_;
  Eigen::MatrixXd covariance = covariance_;
  Teachings taught;
  Eigen::MatrixXd precision;  // the whole reading in natural parameters (only to read it without someone)
  Eigen::VectorXd shift;
  const bool without_each = options_.leave_one_out || options_.jackknife_z > 0;
  if (options_.annotator_sd > 0 || without_each) {
    taught = teachings();
    whole_reading(taught, precision, shift);
  }
  if (options_.annotator_sd > 0) gaussian_of(precision, shift, mean, covariance);
  Eigen::VectorXd mode = mode_of(mean, covariance);
  if (without_each) {
    std::vector<std::string> names;         // the named annotators with a proper belief without them
    std::vector<Eigen::VectorXd> withouts;  // the moves from the prior's without each of them
    for (const auto& [annotator, teaching] : taught) {
      Eigen::VectorXd mean_without;
      Eigen::MatrixXd covariance_without;
      if (annotator.empty() ||
          !gaussian_of(precision - teaching.first, shift - teaching.second, mean_without, covariance_without))
        continue;  // no name, or no proper belief without them: their answers stay
      names.push_back(annotator);
      withouts.push_back(mode_of(mean_without, covariance_without) - start);
    }
    if (options_.leave_one_out) {
      mode = start + smallest_move(mode - start, withouts);
    } else {
      const double z = options_.jackknife_if_it_predicts
                           ? held_out_jackknife(taught, precision, shift, names, withouts, start, mode_of)
                           : options_.jackknife_z;
      if (z > 0) mode = start + jackknifed_move(mode - start, withouts, z);
    }
  }
  m.matrix = Eigen::Map<const Eigen::MatrixXd>(mode.data(), c, s);
  m.pairs = observed_;
  m.covariance = std::move(covariance);
  return m;
}

int MapBelief::agreements(const Eigen::VectorXd& map, const std::string& annotator) const {
  const Eigen::Index c = prior_.matrix.rows();
  int agreed = 0;
  for (const Site& site : sites_) {
    if (site.annotator != annotator) continue;
    Eigen::VectorXd face = Eigen::VectorXd::Zero(c);  // the map's controller weights, inside the ranges
    for (const Eigen::Index s : used_shapes(site.recipe)) face += site.recipe(s) * map.segment(s * c, c);
    face = face.cwiseMax(lower_).cwiseMin(upper_);
    const Eigen::VectorXd to_positive = site.positive - face, to_negative = site.negative - face;
    if (to_positive.dot(site.metric * to_positive) < to_negative.dot(site.metric * to_negative)) ++agreed;
  }
  return agreed;
}

double MapBelief::held_out_jackknife(
    const Teachings& taught, const Eigen::MatrixXd& precision, const Eigen::VectorXd& shift,
    const std::vector<std::string>& names, const std::vector<Eigen::VectorXd>& withouts, const Eigen::VectorXd& start,
    const std::function<Eigen::VectorXd(const Eigen::VectorXd&, const Eigen::MatrixXd&)>& mode_of) const {
  std::map<std::pair<size_t, size_t>, Eigen::VectorXd> pair_moves;  // (a < b) -> the move without both
  for (size_t a = 0; a < names.size(); ++a)
    for (size_t b = a + 1; b < names.size(); ++b) {
      Eigen::VectorXd mean;
      Eigen::MatrixXd covariance;
      const auto& [l_a, h_a] = taught.at(names[a]);
      const auto& [l_b, h_b] = taught.at(names[b]);
      if (gaussian_of(precision - l_a - l_b, shift - h_a - h_b, mean, covariance))
        pair_moves.emplace(std::make_pair(a, b), mode_of(mean, covariance) - start);
    }
  std::vector<double> strengths{0, options_.jackknife_z};  // 0: pooled
  strengths.insert(strengths.end(), options_.jackknife_alternatives.begin(), options_.jackknife_alternatives.end());
  std::sort(strengths.begin(), strengths.end());
  strengths.erase(std::unique(strengths.begin(), strengths.end()), strengths.end());
  std::vector<int> agreed(strengths.size(), 0);
  for (size_t a = 0; a < names.size(); ++a) {
    std::vector<Eigen::VectorXd> pairs;  // the moves without a and each other annotator
    for (size_t b = 0; b < names.size(); ++b)
      if (const auto it = pair_moves.find(std::minmax(a, b)); b != a && it != pair_moves.end())
        pairs.push_back(it->second);
    for (size_t k = 0; k < strengths.size(); ++k)  // at z 0 the jackknifed move is the pooled one
      agreed[k] += agreements(start + jackknifed_move(withouts[a], pairs, strengths[k]), names[a]);
  }
  const size_t best = static_cast<size_t>(std::max_element(agreed.begin(), agreed.end()) - agreed.begin());
  std::string table;
  for (size_t k = 0; k < strengths.size(); ++k)
    table += k == 0 ? fmt::format(" pooled reading {}", agreed[k])
                    : fmt::format(", jackknifed at z {} {}", strengths[k], agreed[k]);
  log::info("rig head: held-out annotators' answers agreed with,{}: the {}", table,
            best == 0 ? std::string("pooled") : fmt::format("jackknifed at z {}", strengths[best]));
  return strengths[best];
}

void MapBelief::whole_reading(const Teachings& taught, Eigen::MatrixXd& precision, Eigen::VectorXd& shift) const {
  if (options_.annotator_sd <= 0) {  // the pooled belief's own
    const Eigen::LDLT<Eigen::MatrixXd> whole(covariance_);
    precision = whole.solve(Eigen::MatrixXd::Identity(mean_.size(), mean_.size()));
    shift = whole.solve(mean_);
    return;
  }
  const Eigen::VectorXd prior_mean = Eigen::Map<const Eigen::VectorXd>(prior_.matrix.data(), mean_.size());
  precision = prior_variance_.cwiseInverse().asDiagonal();
  shift = prior_mean.cwiseQuotient(prior_variance_);
  for (const auto& [annotator, teaching] : taught) {
    precision += teaching.first;
    shift += teaching.second;
  }
}

MapBelief::Teachings MapBelief::teachings() const {
  const Eigen::Index d = mean_.size(), c = prior_.matrix.rows();
  Teachings taught;  // annotator -> (L_a, h_a), their factors summed
  for (const Site& site : sites_) {
    if (site.direction.size() == 0) continue;
    const auto it = taught.try_emplace(site.annotator, Eigen::MatrixXd::Zero(d, d), Eigen::VectorXd::Zero(d)).first;
    it->second.first.selfadjointView<Eigen::Lower>().rankUpdate(site.direction, site.tau);
    it->second.second += site.nu * site.direction;
  }
  const Eigen::VectorXd root =  // R^1/2, D
      (options_.annotator_sd * (upper_ - lower_)).replicate(d / c, 1);
  for (auto& [annotator, teaching] : taught) {
    teaching.first = Eigen::MatrixXd(teaching.first.selfadjointView<Eigen::Lower>());  // the whole L_a
    if (options_.annotator_sd <= 0 || annotator.empty()) continue;                     // answers as they are
    const Eigen::MatrixXd b = root.asDiagonal() * teaching.first * root.asDiagonal();
    const Eigen::LDLT<Eigen::MatrixXd> one_plus_b(Eigen::MatrixXd::Identity(d, d) + b);
    // B (I + B)^-1 = I - (I + B)^-1 (B and (I + B)^-1 commute).
    const Eigen::MatrixXd read = Eigen::MatrixXd::Identity(d, d) - one_plus_b.solve(Eigen::MatrixXd::Identity(d, d));
    teaching.first = root.cwiseInverse().asDiagonal() * read * root.cwiseInverse().asDiagonal();
    teaching.second = root.cwiseInverse().asDiagonal() * one_plus_b.solve(root.cwiseProduct(teaching.second));
  }
  return taught;
}

bool MapBelief::gaussian_of(Eigen::MatrixXd precision, const Eigen::VectorXd& shift, Eigen::VectorXd& mean,
                            Eigen::MatrixXd& covariance) {
  precision = 0.5 * (precision + precision.transpose());
  const Eigen::LDLT<Eigen::MatrixXd> solver(precision);
  covariance = solver.solve(Eigen::MatrixXd::Identity(precision.rows(), precision.cols()));
  covariance = 0.5 * (covariance + covariance.transpose());
  mean = covariance * shift;
  return solver.info() == Eigen::Success && solver.isPositive() && (solver.vectorD().array() > 0).all();
}

}  // namespace retarget
