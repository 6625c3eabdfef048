#include "geometry/rotation.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>

namespace retarget {

namespace {

PolarDecomposition polar_by_svd(const Eigen::Matrix3d& T) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(T, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d& U = svd.matrixU();
  const Eigen::Matrix3d& V = svd.matrixV();
  Eigen::Vector3d d(1, 1, (U * V.transpose()).determinant() < 0 ? -1 : 1);
  PolarDecomposition p;
  p.rotation = U * d.asDiagonal() * V.transpose();
  p.stretch = V * (d.cwiseProduct(svd.singularValues())).asDiagonal() * V.transpose();
  return p;
}

// Transposed inverse of X by cofactors, given det(X).
inline Eigen::Matrix3d inverse_transpose(const Eigen::Matrix3d& X, double det) {
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
  return C / det;
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
  // Reflections and (near-)singular gradients: only the SVD gives the rotation we want.
  if (!(norm > 0) || !(det > 1e-9 * norm * norm * norm)) return polar_by_svd(T);
  // Most DR gradients are a rotation times a mild stretch. Near orthogonality, Newton-Schulz
  // X <- X (I - (X^T X - I) / 2) needs only products; further away, Higham's scaled Newton
  // step X <- (g X + X^-T / g) / 2 brings X close in a few steps. Both converge to the
  // orthogonal polar factor, which has det +1 here.
  Eigen::Matrix3d X = T * (std::sqrt(3.0) / norm);
  double d = det * (3.0 * std::sqrt(3.0) / (norm * norm * norm));
  for (int iteration = 0; iteration < 40; ++iteration) {
    Eigen::Matrix3d E = X.transpose() * X;
    E.diagonal().array() -= 1.0;
    const double error = E.squaredNorm();
    if (error < 1e-24) return from_rotation(X, T);
    if (error < 0.25) {
      X -= 0.5 * X * E;
      // |E| shrinks to ~0.75 |E|^2 per step: below 1e-4 one more step leaves X orthogonal
      // to ~1e-8, well past the float precision the features are stored in.
      if (error < 1e-8) return from_rotation(X, T);
    } else {
      const Eigen::Matrix3d Y = inverse_transpose(X, d);
      const double gamma = std::sqrt(std::sqrt(Y.squaredNorm() / X.squaredNorm()));
      X = 0.5 * (gamma * X + Y / gamma);
      d = X.determinant();
    }
  }
  return polar_by_svd(T);
}

namespace {
// atan(x) / x for 0 <= x <= 0.25 by its Taylor series (error < 1e-12), which is what most
// per-vertex rotations need; the library atan2 costs several times more.
double atan_over_x(double x) {
  const double x2 = x * x;
  double sum = 1.0 / 15;
  for (int k = 13; k >= 1; k -= 2) sum = 1.0 / k - x2 * sum;
  return sum;
}
}  // namespace

Eigen::Vector3d rotation_log(const Eigen::Matrix3d& R) {
  Eigen::Quaterniond q(R);
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const Eigen::Vector3d v = q.vec();
  const double s = v.norm();
  // angle = 2 atan2(s, w) and the axis is v / s, so log R = (angle / s) v.
  if (s <= 0.25 * q.w()) return (2.0 * atan_over_x(s / q.w()) / q.w()) * v;
  return (2.0 * std::atan2(s, q.w()) / s) * v;
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
