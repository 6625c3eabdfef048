// Best rigid (optionally similarity) transform between two point sets with known
// correspondence: Kabsch, with Umeyama's scale.
#pragma once

#include <Eigen/Core>

#include "geometry/mesh.h"

namespace retarget {

// x -> scale * rotation * x + translation.
struct RigidTransform {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  double scale = 1.0;

  Positions apply(const Positions& points) const;  // #P x 3 -> #P x 3
};

struct RigidAlignmentOptions {
  bool with_scale = false;  // Umeyama's uniform scale as well
  Eigen::VectorXd weights;  // #P non-negative weights; empty = all ones
};

// Minimises sum_i w_i |s R from_i + t - to_i|^2 (R a proper rotation, never a reflection).
// from, to: #P x 3 corresponding points (P >= 1). Throws retarget::Error when the counts
// differ, weights have the wrong size or are negative, or all weights are zero.
RigidTransform rigid_alignment(const Positions& from, const Positions& to, const RigidAlignmentOptions& options = {});

}  // namespace retarget
