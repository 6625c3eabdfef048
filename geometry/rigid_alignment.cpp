#include "geometry/rigid_alignment.h"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <string>

#include "core/error.h"

namespace retarget {

Positions RigidTransform::apply(const Positions& points) const {
  Positions out = (scale * points * rotation.transpose()).rowwise() + translation.transpose();
  return out;
}

RigidTransform rigid_alignment(const Positions& from, const Positions& to, const RigidAlignmentOptions& options) {
  const Eigen::Index n = from.rows();
  if (to.rows() != n)
    throw Error("rigid alignment", "point counts differ: " + std::to_string(n) + " and " + std::to_string(to.rows()));
  if (n == 0) throw Error("rigid alignment", "no points to align");
  Eigen::VectorXd w = options.weights.size() ? options.weights : Eigen::VectorXd::Ones(n);
  if (w.size() != n)
    throw Error("rigid alignment", "got " + std::to_string(w.size()) + " weights for " + std::to_string(n) + " points");
  if ((w.array() < 0).any()) throw Error("rigid alignment", "weights must be non-negative");
  const double total = w.sum();
  if (!(total > 0)) throw Error("rigid alignment", "all weights are zero");

  const Eigen::RowVector3d mean_from = (w.transpose() * from) / total;
  const Eigen::RowVector3d mean_to = (w.transpose() * to) / total;
  const Positions a = from.rowwise() - mean_from;
  const Positions b = to.rowwise() - mean_to;
  const Eigen::Matrix3d covariance = b.transpose() * w.asDiagonal() * a / total;

  Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d d(1, 1, (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1);
  RigidTransform t;
  t.rotation = svd.matrixU() * d.asDiagonal() * svd.matrixV().transpose();
  if (options.with_scale) {
    const double variance = (a.rowwise().squaredNorm().transpose() * w)(0) / total;
    if (variance > 0) t.scale = svd.singularValues().dot(d) / variance;
  }
  t.translation = mean_to.transpose() - t.scale * t.rotation * mean_from.transpose();
  return t;
}

}  // namespace retarget
