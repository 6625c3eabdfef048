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

// exp of a rotation vector r (Rodrigues), accurate for |r| -> 0.
Eigen::Matrix3d rotation_exp(const Eigen::Vector3d& r);

}  // namespace retarget
