#include "correspond/belief_search.h"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "correspond/belief_box.h"

namespace retarget {

namespace {

void check_sizes(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, Eigen::Index c, const char* what) {
  if (lower.size() != c || upper.size() != c)
    throw Error("correspond.belief",
                fmt::format("{}: {} controllers but ranges for {} and {}", what, c, lower.size(), upper.size()));
}

Eigen::VectorXd clamped(const Eigen::VectorXd& w, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  return w.cwiseMax(lower).cwiseMin(upper);
}

// The squared face distance from a to the belief: to its mean, plus its spread.
double expected_squared_distance(const Belief& b, const Eigen::MatrixXd& g, const Eigen::VectorXd& a) {
  const Eigen::VectorXd d = a - b.mean;
  return d.dot(g * d) + (g * b.covariance).trace();
}

// What the belief expects of x = n'c + offset for one pair (header): its mean m and variance v,
// and the spread of the answer's own noise (perception and readings).
struct Cut {
  Eigen::VectorXd n;  // C; empty when the two faces do not differ
  double m = 0, v = 0, noise = 0;
};

Cut cut_of(const Belief& belief, const Eigen::MatrixXd& metric, const Eigen::VectorXd& positive,
           const Eigen::VectorXd& negative, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
           const BeliefSearchOptions& options) {
  Cut cut;
  const Eigen::VectorXd n = 2.0 * metric * (positive - negative);
  if (n.squaredNorm() < 1e-24) return cut;
  cut.n = n;
  const double offset = negative.dot(metric * negative) - positive.dot(metric * positive);
  cut.m = n.dot(belief.mean) + offset;
  cut.v = n.dot(belief.covariance * n);
  const double da = std::sqrt(expected_squared_distance(belief, metric, positive));
  const double db = std::sqrt(expected_squared_distance(belief, metric, negative));
  const double t = options.weber * (da + db) * (da + db) / std::sqrt(2.0);
  const Eigen::VectorXd reading = (options.reading_sd * (upper - lower)).array().square().matrix();
  cut.noise = std::sqrt(t * t + n.cwiseProduct(n).dot(reading));
  return cut;
}

// Bits the answer is expected to tell about c (Houlsby et al. 2011, "BALD", for a probit):
// the entropy of the predicted answer less the expected entropy of the answer given c.
double expected_bits(const Cut& cut) {
  if (cut.n.size() == 0 || !(cut.noise > 0)) return 0;
  const double mu = cut.m / cut.noise, var = cut.v / (cut.noise * cut.noise);
  const double p = 0.5 * std::erfc(-mu / std::sqrt(2.0 * (var + 1)));
  const auto entropy = [](double q) {
    return q <= 0 || q >= 1 ? 0.0 : -(q * std::log2(q) + (1 - q) * std::log2(1 - q));
  };
  const double c2 = M_PI * std::log(2.0) / 2;
  return entropy(p) - std::sqrt(c2 / (var + c2)) * std::exp(-mu * mu / (2 * (var + c2)));
}

}  // namespace

void BeliefSearchOptions::validate(const std::string& key_path) const {
  const auto positive = [&](double v, const char* field, const char* what) {
    if (!std::isfinite(v) || v <= 0)
      throw Error(key_path + "." + field, fmt::format("expected {} above 0, got {}", what, v));
  };
  positive(prior_sd, "prior_sd", "a prior spread (a fraction of each controller's range)");
  positive(weber, "weber", "a perception noise (a fraction of a judged distance)");
  positive(step, "step", "a step (in the belief's standard deviations)");
  if (!std::isfinite(off_table) || off_table <= 0 || off_table > 1)
    throw Error(key_path + ".off_table", fmt::format("expected a fraction in (0, 1], got {}", off_table));
  if (!std::isfinite(reading_sd) || reading_sd < 0)
    throw Error(key_path + ".reading_sd", fmt::format("expected a spread of 0 or more, got {}", reading_sd));
  if (!std::isfinite(sparsity) || sparsity < 0)
    throw Error(key_path + ".sparsity", fmt::format("expected a pull of 0 or more, got {}", sparsity));
  if (!std::isfinite(annotator_sd) || annotator_sd < 0)
    throw Error(key_path + ".annotator_sd", fmt::format("expected a spread of 0 or more, got {}", annotator_sd));
  if (!std::isfinite(jackknife_z) || jackknife_z < 0)
    throw Error(key_path + ".jackknife_z", fmt::format("expected a threshold of 0 or more, got {}", jackknife_z));
  for (const double z : jackknife_alternatives)
    if (!std::isfinite(z) || z < 0)
      throw Error(key_path + ".jackknife_alternatives", fmt::format("expected thresholds of 0 or more, got {}", z));
  if (refine_passes < 0)
    throw Error(key_path + ".refine_passes", fmt::format("expected 0 or more passes, got {}", refine_passes));
  if (!std::isfinite(lapse) || lapse < 0 || lapse >= 0.5)
    throw Error(key_path + ".lapse", fmt::format("expected a probability in [0, 0.5), got {}", lapse));
}

BeliefSearchOptions BeliefSearchOptions::map_reading() {
  BeliefSearchOptions o;
  o.reading_sd = 0.35;
  o.refine_passes = 3;
  o.jackknife_z = 1;
  o.jackknife_if_it_predicts = true;
  o.jackknife_alternatives = {2};
  return o;
}

Belief prior_belief(const Eigen::VectorXd& start, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                    const BeliefSearchOptions& options) {
  options.validate();
  check_sizes(lower, upper, start.size(), "prior");
  const Eigen::VectorXd range = upper - lower;
  for (Eigen::Index i = 0; i < range.size(); ++i)
    if (!(range(i) > 0))
      throw Error("correspond.belief", fmt::format("controller {} has an empty range [{}, {}]", i, lower(i), upper(i)));
  Belief b;
  b.mean = clamped(start, lower, upper);
  b.covariance = (options.prior_sd * range).array().square().matrix().asDiagonal();
  return b;
}

CutUpdate comparison_update(const Belief& belief, const Eigen::MatrixXd& metric, const Eigen::VectorXd& positive,
                            const Eigen::VectorXd& negative, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                            const BeliefSearchOptions& options) {
  const Eigen::Index c = belief.mean.size();
  check_sizes(lower, upper, c, "comparison");
  if (positive.size() != c || negative.size() != c || metric.rows() != c || metric.cols() != c)
    throw Error("correspond.belief", fmt::format("a comparison of {} and {} weights in a metric {}x{}, belief over {}",
                                                 positive.size(), negative.size(), metric.rows(), metric.cols(), c));
  CutUpdate u;
  const Cut cut = cut_of(belief, metric, positive, negative, lower, upper, options);
  if (cut.n.size() == 0) return u;
  const double spread = std::sqrt(cut.noise * cut.noise + cut.v);
  // Z = lapse / 2 + (1 - lapse) Phi(alpha): the answer's probability under the belief; its
  // log's first and second derivatives in m move the mean and shrink the covariance.
  const double alpha = cut.m / spread;
  const double phi = std::exp(-0.5 * alpha * alpha) / std::sqrt(2.0 * M_PI);
  const double cdf = 0.5 * std::erfc(-alpha / std::sqrt(2.0));
  const double z = options.lapse / 2 + (1 - options.lapse) * cdf;
  u.n = cut.n;
  if (z > 1e-300) {
    u.gain = (1 - options.lapse) * phi / (spread * z);
    u.curvature = -(1 - options.lapse) * alpha * phi / (spread * spread * z) - u.gain * u.gain;
  } else {  // lapse 0 and an answer far against the belief: Phi's tail, phi / Phi -> -alpha
    u.gain = -alpha / spread;
    u.curvature = -1 / (spread * spread);
  }
  return u;
}

void observe(Belief& belief, const Eigen::MatrixXd& metric, const Eigen::VectorXd& positive,
             const Eigen::VectorXd& negative, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
             const BeliefSearchOptions& options) {
  const CutUpdate u = comparison_update(belief, metric, positive, negative, lower, upper, options);
  if (u.n.size() == 0) return;
  const Eigen::VectorXd sigma_n = belief.covariance * u.n;
  belief.mean += sigma_n * u.gain;
  belief.covariance += sigma_n * sigma_n.transpose() * u.curvature;
  belief.covariance = 0.5 * (belief.covariance + belief.covariance.transpose());
}

std::array<Eigen::VectorXd, 2> most_informative_pair(const Belief& belief, const Eigen::MatrixXd& metric,
                                                     const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                                                     const BeliefSearchOptions& options) {
  const Eigen::Index c = belief.mean.size();
  check_sizes(lower, upper, c, "pair");
  if (metric.rows() != c || metric.cols() != c)
    throw Error("correspond.belief",
                fmt::format("a metric {}x{} for a belief over {}", metric.rows(), metric.cols(), c));
  // G = L L' (a little ridge for controllers that barely move the face); with u = L^-T e the
  // generalised problem G Sigma G u = lambda G u becomes L' Sigma L e = lambda e.
  const double ridge = 1e-9 * std::max(metric.trace() / static_cast<double>(c), 1e-300);
  const Eigen::LLT<Eigen::MatrixXd> llt(metric + ridge * Eigen::MatrixXd::Identity(c, c));
  if (llt.info() != Eigen::Success) throw Error("correspond.belief", "the face metric is not positive definite");
  const Eigen::MatrixXd l = llt.matrixL();
  // Only the part of the belief inside the ranges is worth asking about.
  const Belief inside = truncated_belief(belief, lower, upper);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(l.transpose() * inside.covariance * l);
  const Eigen::VectorXd centre = box_mode(belief, lower, upper);
  // Candidates: the centre +- a step along each eigen-direction, at step, step / 2 and step / 4
  // of the belief's sd there, clamped into the ranges; the one the answer of which is expected to
  // tell the most wins (a direction whose spread lies outside the ranges, or whose answer the
  // belief already predicts, tells little). Ties keep the direction of larger spread.
  std::array<Eigen::VectorXd, 2> best{clamped(centre, lower, upper), clamped(centre, lower, upper)};
  double best_bits = -1;
  for (Eigen::Index j = c - 1; j >= 0; --j) {  // eigenvalues ascend
    Eigen::VectorXd e = eigen.eigenvectors().col(j);
    Eigen::Index largest = 0;
    e.cwiseAbs().maxCoeff(&largest);
    if (e(largest) < 0) e = -e;  // one sign on every machine
    Eigen::VectorXd u = l.transpose().triangularView<Eigen::Upper>().solve(e);
    u.normalize();
    const double sd = std::sqrt(std::max(u.dot(inside.covariance * u), 0.0));
    for (const double fraction : {1.0, 0.5, 0.25}) {
      const Eigen::VectorXd step = fraction * options.step * sd * u;
      std::array<Eigen::VectorXd, 2> pair{clamped(centre + step, lower, upper), clamped(centre - step, lower, upper)};
      const double bits = expected_bits(cut_of(belief, metric, pair[0], pair[1], lower, upper, options));
      if (bits > best_bits + 1e-12) {
        best_bits = bits;
        best = std::move(pair);
      }
    }
  }
  return best;
}

Eigen::VectorXd belief_estimate(const Belief& belief, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  check_sizes(lower, upper, belief.mean.size(), "estimate");
  return box_mode(belief, lower, upper);
}

}  // namespace retarget
