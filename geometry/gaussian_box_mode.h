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

}  // namespace retarget
