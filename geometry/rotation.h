// 3 x 3 rotation maths used per vertex on the hot path: polar decomposition, and the
// matrix logarithm and exponential of rotations. All are allocation-free.
#pragma once

#include <Eigen/Core>

namespace retarget {

struct PolarDecomposition {
  Eigen::Matrix3d rotation;  // R, a proper rotation (det +1)
  Eigen::Matrix3d stretch;   // S, symmetric, with T = R S
};

// T = R S with R a rotation and S symmetric. For det(T) > 0 this is the ordinary polar
// decomposition, computed by Newton-Schulz steps near orthogonality and Higham's scaled
// Newton steps further away; R is orthogonal to ~1e-8 (the features are stored as floats).
// Reflections (det(T) <= 0) and near-singular T go through the eigen-decomposition of T^T T,
// which gives what the SVD T = U Sigma V^T would with R = U D V^T, S = V D Sigma V^T,
// D = diag(1, 1, det(U V^T)) (the smallest singular direction flipped). Never returns NaN
// for finite T.
PolarDecomposition polar_decomposition(const Eigen::Matrix3d& T);

// log R as a rotation vector (axis * angle, angle in [0, pi]), accurate near 0 (series)
// and near pi (through the quaternion, never acos of the trace).
Eigen::Vector3d rotation_log(const Eigen::Matrix3d& R);

// atan(x) / x for 0 <= x <= 0.25 by its Taylor series (error < 1e-12): what rotation_log uses for
// rotations up to ~14 degrees, where the library atan2 costs several times more. Inline so that
// the vector lanes of geometry/dr_pack_lanes.h compute the same series lane by lane.
inline double atan_over_x(double x) {
  const double x2 = x * x;
  double sum = 1.0 / 15;
#pragma GCC unroll 7
  for (int k = 13; k >= 1; k -= 2) sum = 1.0 / k - x2 * sum;
  return sum;
}

// exp of a rotation vector r (Rodrigues), accurate for |r| -> 0.
Eigen::Matrix3d rotation_exp(const Eigen::Vector3d& r);

}  // namespace retarget
