// The most likely point of a Gaussian inside a box: argmin over lower <= x <= upper of
// (x - mean)' Sigma^-1 (x - mean). A controller map with its uncertainty (geometry/controller_map.h)
// reads a face this way, so that controllers the belief pushes past their range land on it with
// the others moved as the correlations say, where clamping each alone would not.
// Shapes: mean, lower, upper [n]; covariance [n, n] symmetric positive semi-definite; float64.
#pragma once

#include <Eigen/Core>

namespace retarget {

// By coordinate descent on the precision (a small ridge keeps a covariance that is exactly
// singular, e.g. zero, usable: the mean is then kept where it is known). Throws retarget::Error
// for sizes that differ.
Eigen::VectorXd gaussian_box_mode(const Eigen::VectorXd& mean, const Eigen::MatrixXd& covariance,
                                  const Eigen::VectorXd& lower, const Eigen::VectorXd& upper);

// A sparse pull towards `centre` on top of it: argmin over the box of
// (x - mean)' Sigma^-1 (x - mean) / 2 + sum_j pull_j |x_j - centre_j| (a Laplace prior: each x_j
// stays at centre_j unless the Gaussian's evidence for moving it outweighs pull_j), by
// coordinate descent with soft thresholding. `centre` inside the box; pull [n] >= 0 (0: the
// plain box mode). Throws retarget::Error for sizes that differ.
Eigen::VectorXd sparse_box_mode(const Eigen::VectorXd& mean, const Eigen::MatrixXd& covariance,
                                const Eigen::VectorXd& centre, const Eigen::VectorXd& pull,
                                const Eigen::VectorXd& lower, const Eigen::VectorXd& upper);

}  // namespace retarget
