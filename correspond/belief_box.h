// The belief search's belief inside the controllers' ranges (correspond/belief_search.h): a
// Gaussian knows nothing of the rig's bounds, yet most of an expression's controllers sit on one
// (at rest), and a belief that leans past a bound would ask about faces the rig cannot make.
// Shapes as there: C-vectors and C x C matrices, float64.
#pragma once

#include <Eigen/Core>

#include "correspond/belief_search.h"

namespace retarget {

// The Gaussian matching the moments of `belief` truncated to the box [lower, upper], by
// expectation propagation over the 2C bounds (one Gaussian site each, `sweeps` sweeps).
Belief truncated_belief(const Belief& belief, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                        int sweeps = 8);

// The belief's most likely weights inside the box: argmin over [lower, upper] of
// (c - mean)' Sigma^-1 (c - mean). On a bound where the belief leans past it, with the
// correlations kept (clamping each controller alone would not).
Eigen::VectorXd box_mode(const Belief& belief, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper);

}  // namespace retarget
