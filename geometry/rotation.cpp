#include "geometry/rotation.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>

namespace retarget {

namespace {

// T = R S for any T, from the eigen-decomposition of T^T T = V Sigma^2 V^T (cheaper than
// a 3 x 3 SVD): with V a proper rotation and Sigma ascending, u_k = T v_k / sigma_k for the
// two largest singular values and u_0 = u_1 x u_2, so R = U V^T is a rotation (the SVD's
// det(U V^T) correction) even for reflections and rank-deficient T.
PolarDecomposition polar_by_eigen(const Eigen::Matrix3d& T) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(T.transpose() * T);
  Eigen::Matrix3d V = eig.eigenvectors();
  V.col(0) = V.col(1).cross(V.col(2));
  const Eigen::Vector3d sigma = eig.eigenvalues().cwiseMax(0).cwiseSqrt();
  Eigen::Matrix3d U;
  if (sigma[1] > 1e-12 * std::max(sigma[2], 1e-300)) {
    U.col(2) = (T * V.col(2)).normalized();
    U.col(1) = T * V.col(1);
    U.col(1) = (U.col(1) - U.col(1).dot(U.col(2)) * U.col(2)).normalized();
  } else if (sigma[2] > 0) {  // rank one: any rotation taking v_2 to u_2 will do
    U.col(2) = (T * V.col(2)).normalized();
    U.col(1) = U.col(2).unitOrthogonal();
  } else {  // T = 0
    U = V;
  }
  U.col(0) = U.col(1).cross(U.col(2));
  PolarDecomposition p;
  p.rotation = U * V.transpose();
  const Eigen::Matrix3d S = p.rotation.transpose() * T;
  p.stretch = 0.5 * (S + S.transpose());
  return p;
}

// Transposed inverse of X by cofactors (det(X) from the same cofactors).
inline Eigen::Matrix3d inverse_transpose(const Eigen::Matrix3d& X) {
  Eigen::Matrix3d C;
  C(0, 0) = X(1, 1) * X(2, 2) - X(1, 2) * X(2, 1);
  C(0, 1) = X(1, 2) * X(2, 0) - X(1, 0) * X(2, 2);
  C(0, 2) = X(1, 0) * X(2, 1) - X(1, 1) * X(2, 0);
  C(1, 0) = X(0, 2) * X(2, 1) - X(0, 1) * X(2, 2);
  C(1, 1) = X(0, 0) * X(2, 2) - X(0, 2) * X(2, 0);
  C(1, 2) = X(0, 1) * X(2, 0) - X(0, 0) * X(2, 1);
  C(2, 0) = X(0, 1) * X(1, 2) - X(0, 2) * X(1, 1);
  C(2, 1) = X(0, 2) * X(1, 0) - X(0, 0) * X(1, 2);
  C(2, 2) = X(0, 0) * X(1, 1) - X(0, 1) * X(1, 0);
  return C / (X(0, 0) * C(0, 0) + X(0, 1) * C(0, 1) + X(0, 2) * C(0, 2));
}

}  // namespace

namespace {
PolarDecomposition from_rotation(const Eigen::Matrix3d& R, const Eigen::Matrix3d& T) {
  PolarDecomposition p;
  p.rotation = R;
  const Eigen::Matrix3d S = R.transpose() * T;
  p.stretch = 0.5 * (S + S.transpose());
  return p;
}
}  // namespace

PolarDecomposition polar_decomposition(const Eigen::Matrix3d& T) {
  const double norm = T.norm();
  const double det = T.determinant();
  // Reflections and (near-)singular gradients: the eigen path gives the rotation we want.
  if (!(norm > 0) || !(det > 1e-9 * norm * norm * norm)) return polar_by_eigen(T);
  // Most DR gradients are a rotation times a mild stretch. Near orthogonality, Newton-Schulz
  // X <- X (I - (X^T X - I) / 2) needs only products; further away, Higham's scaled Newton
  // step X <- (g X + X^-T / g) / 2 brings X close in a few steps. Both converge to the
  // orthogonal polar factor, which has det +1 here.
  Eigen::Matrix3d X = T * (std::sqrt(3.0) / norm);
  for (int iteration = 0; iteration < 40; ++iteration) {
    // E = X^T X - I, symmetric: six entries, written out because this loop is the hottest
    // code of feature extraction and Eigen's generic 3 x 3 products are slower here.
    const double* x = X.data();  // column-major: x[3 * c + r]
    const double e00 = x[0] * x[0] + x[1] * x[1] + x[2] * x[2] - 1;
    const double e11 = x[3] * x[3] + x[4] * x[4] + x[5] * x[5] - 1;
    const double e22 = x[6] * x[6] + x[7] * x[7] + x[8] * x[8] - 1;
    const double e01 = x[0] * x[3] + x[1] * x[4] + x[2] * x[5];
    const double e02 = x[0] * x[6] + x[1] * x[7] + x[2] * x[8];
    const double e12 = x[3] * x[6] + x[4] * x[7] + x[5] * x[8];
    const double error = e00 * e00 + e11 * e11 + e22 * e22 + 2 * (e01 * e01 + e02 * e02 + e12 * e12);
    if (error < 1e-24) return from_rotation(X, T);
    if (error < 0.25) {
      // X <- X (I - E / 2), column by column: column c of X E is sum_k X.col(k) E(k, c).
      const Eigen::Vector3d c0 = X.col(0), c1 = X.col(1), c2 = X.col(2);
      X.col(0) -= 0.5 * (c0 * e00 + c1 * e01 + c2 * e02);
      X.col(1) -= 0.5 * (c0 * e01 + c1 * e11 + c2 * e12);
      X.col(2) -= 0.5 * (c0 * e02 + c1 * e12 + c2 * e22);
      // |E| shrinks to ~0.75 |E|^2 per step: below 1e-4 one more step leaves X orthogonal
      // to ~1e-8, well past the float precision the features are stored in.
      if (error < 1e-8) return from_rotation(X, T);
    } else {
      const Eigen::Matrix3d Y = inverse_transpose(X);
      const double gamma = std::sqrt(std::sqrt(Y.squaredNorm() / X.squaredNorm()));
      X = 0.5 * (gamma * X + Y / gamma);
    }
  }
  return polar_by_eigen(T);
}

Eigen::Vector3d rotation_log(const Eigen::Matrix3d& R) {
  // Up to ~150 degrees the axis comes straight from the skew part, v = sin(angle) axis, and
  // the angle from atan2(|v|, cos(angle)); near pi |v| vanishes and the axis is only in the
  // symmetric part, which the quaternion extraction handles.
  const double c = 0.5 * (R.trace() - 1);
  if (c > -0.85) {
    const Eigen::Vector3d v(0.5 * (R(2, 1) - R(1, 2)), 0.5 * (R(0, 2) - R(2, 0)), 0.5 * (R(1, 0) - R(0, 1)));
    const double s = v.norm();
    if (s <= 0.25 * c) return (atan_over_x(s / c) / c) * v;  // angle / sin(angle), by series
    return (std::atan2(s, c) / s) * v;
  }
  Eigen::Quaterniond q(R);
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const Eigen::Vector3d v = q.vec();
  const double s = v.norm();
  return (2.0 * std::atan2(s, q.w()) / s) * v;  // s >= sin(74 degrees) here
}

Eigen::Matrix3d rotation_exp(const Eigen::Vector3d& r) {
  const double theta2 = r.squaredNorm();
  double a, b;  // sin(t)/t and (1 - cos(t))/t^2
  if (theta2 < 1e-8) {
    a = 1 - theta2 / 6;
    b = 0.5 - theta2 / 24;
  } else {
    const double theta = std::sqrt(theta2);
    a = std::sin(theta) / theta;
    b = (1 - std::cos(theta)) / theta2;
  }
  Eigen::Matrix3d K;
  K << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
  return Eigen::Matrix3d::Identity() + a * K + b * K * K;
}

}  // namespace retarget
