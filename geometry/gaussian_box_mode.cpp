#include "geometry/gaussian_box_mode.h"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace retarget {

Eigen::VectorXd gaussian_box_mode(const Eigen::VectorXd& mean, const Eigen::MatrixXd& covariance,
                                  const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  return sparse_box_mode(mean, covariance, mean, Eigen::VectorXd::Zero(mean.size()), lower, upper);
}

Eigen::VectorXd sparse_box_mode(const Eigen::VectorXd& mean, const Eigen::MatrixXd& covariance,
                                const Eigen::VectorXd& centre, const Eigen::VectorXd& pull,
                                const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  const Eigen::Index n = mean.size();
  if (covariance.rows() != n || covariance.cols() != n || lower.size() != n || upper.size() != n ||
      centre.size() != n || pull.size() != n)
    throw Error("box mode", fmt::format("a mean of {} with a {}x{} covariance, ranges of {} and {}, a centre of {} "
                                        "and pulls of {}",
                                        n, covariance.rows(), covariance.cols(), lower.size(), upper.size(),
                                        centre.size(), pull.size()));
  Eigen::VectorXd x = mean.cwiseMax(lower).cwiseMin(upper);
  if (n == 0) return x;
  const double ridge = 1e-9 * std::max(covariance.trace() / static_cast<double>(n), 1e-12);
  const Eigen::MatrixXd p =
      (covariance + ridge * Eigen::MatrixXd::Identity(n, n)).ldlt().solve(Eigen::MatrixXd::Identity(n, n));
  // Each coordinate in turn to its best value given the others, within its range: the
  // objective never grows, and with p positive definite the sweeps converge. In one coordinate
  // the objective is p_jj (x - z)^2 / 2 + pull_j |x - centre_j|, convex: its minimum is z
  // shrunk towards centre_j by pull_j / p_jj, then clamped into the range.
  for (int sweep = 0; sweep < 500; ++sweep) {
    double moved = 0;
    for (Eigen::Index j = 0; j < n; ++j) {
      const double rest = p.col(j).dot(x - mean) - p(j, j) * (x(j) - mean(j));  // p symmetric: a column is contiguous
      const double z = mean(j) - rest / p(j, j) - centre(j), shrink = pull(j) / p(j, j);
      const double shrunk = centre(j) + (z > shrink ? z - shrink : z < -shrink ? z + shrink : 0.0);
      const double next = std::clamp(shrunk, lower(j), upper(j));
      moved = std::max(moved, std::abs(next - x(j)));
      x(j) = next;
    }
    if (moved < 1e-12) break;
  }
  return x;
}

}  // namespace retarget
