#include "correspond/belief_box.h"

#include <fmt/format.h>

#include <cmath>

#include "core/error.h"
#include "geometry/gaussian_box_mode.h"

namespace retarget {

namespace {

void check_box(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, Eigen::Index c) {
  if (lower.size() != c || upper.size() != c)
    throw Error("correspond.belief",
                fmt::format("a belief over {} controllers but ranges for {} and {}", c, lower.size(), upper.size()));
}

// phi(z) / Phi(z), stable for very negative z (Phi's tail: -z + 1/z asymptotically).
double inverse_mills(double z) {
  if (z < -30) return -z - 1 / z;
  return std::exp(-0.5 * z * z) / std::sqrt(2.0 * M_PI) / (0.5 * std::erfc(-z / std::sqrt(2.0)));
}

}  // namespace

Eigen::VectorXd box_mode(const Belief& belief, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  check_box(lower, upper, belief.mean.size());
  return gaussian_box_mode(belief.mean, belief.covariance, lower, upper);
}

Belief truncated_belief(const Belief& belief, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, int sweeps) {
  const Eigen::Index c = belief.mean.size();
  check_box(lower, upper, c);
  // Expectation propagation with one Gaussian site per bound (c_j >= lower_j, -c_j >= -upper_j):
  // each sweep replaces every site by the one that matches the moments of its cavity times the
  // bound's indicator.
  Belief q = belief;
  Eigen::VectorXd tau = Eigen::VectorXd::Zero(2 * c), nu = Eigen::VectorXd::Zero(2 * c);
  for (int sweep = 0; sweep < sweeps; ++sweep)
    for (Eigen::Index i = 0; i < 2 * c; ++i) {
      const Eigen::Index j = i % c;
      const double sign = i < c ? 1.0 : -1.0, bound = i < c ? lower(j) : -upper(j);
      const double var = q.covariance(j, j), mean = sign * q.mean(j);
      if (!(var > 1e-15)) continue;  // known exactly: nothing to truncate
      const double cavity_precision = 1 / var - tau(i);
      if (!(cavity_precision > 0)) continue;
      const double cavity_var = 1 / cavity_precision, cavity_mean = cavity_var * (mean / var - nu(i));
      const double sd = std::sqrt(cavity_var), z = (cavity_mean - bound) / sd, lambda = inverse_mills(z);
      const double new_mean = cavity_mean + sd * lambda;
      const double new_var = cavity_var * std::max(1 - lambda * (lambda + z), 1e-12);
      const double delta_tau = 1 / new_var - cavity_precision - tau(i);
      const double delta_nu = new_mean / new_var - cavity_mean / cavity_var - nu(i);
      tau(i) += delta_tau;
      nu(i) += delta_nu;
      // Rank-one update of q by the change of site i (direction sign * e_j).
      const Eigen::VectorXd column = sign * q.covariance.col(j);
      const double denominator = 1 + delta_tau * var;
      q.mean += column * (delta_nu - delta_tau * mean) / denominator;
      q.covariance -= column * column.transpose() * (delta_tau / denominator);
    }
  q.covariance = 0.5 * (q.covariance + q.covariance.transpose());
  return q;
}

}  // namespace retarget
