#include "geometry/face_model_fit.h"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>

#include "core/config.h"
#include "core/error.h"

namespace retarget {

void FaceFitOptions::validate(const std::string& key_path) const {
  require(std::isfinite(lo) && std::isfinite(hi) && lo <= hi, key_path + ".lo",
          fmt::format("expected finite bounds with lo <= hi, got [{}, {}]", lo, hi));
  require(std::isfinite(ridge) && ridge >= 0, key_path + ".ridge", fmt::format("expected >= 0, got {}", ridge));
  require(sweeps >= 1, key_path + ".sweeps", fmt::format("expected at least 1, got {}", sweeps));
  require(std::isfinite(tolerance) && tolerance >= 0, key_path + ".tolerance",
          fmt::format("expected >= 0, got {}", tolerance));
}

namespace {

// #V x 3 row-major positions as one column of 3V numbers.
Eigen::VectorXd flatten(const Positions& p) {
  Eigen::VectorXd out(p.rows() * 3);
  for (Eigen::Index v = 0; v < p.rows(); ++v) out.segment<3>(3 * v) = p.row(v).transpose();
  return out;
}

}  // namespace

FaceModelFit::FaceModelFit(const FaceModel& model, const FaceFitOptions& options) : options_(options) {
  options_.validate();
  if (model.expressions.empty()) throw Error(model.source, "the face model has no expression shapes to fit");
  const Eigen::Index n = model.neutral.vertex_count() * 3;
  const Eigen::Index e = static_cast<Eigen::Index>(model.expressions.size());
  neutral_ = flatten(model.neutral.vertices);
  Eigen::MatrixXd shapes(n, e);
  for (Eigen::Index j = 0; j < e; ++j) {
    shapes.col(j) = flatten(model.expressions[static_cast<size_t>(j)].offset);
    shapes_.push_back(model.expressions[static_cast<size_t>(j)].name);
  }
  projected_ = shapes;
  if (!model.identities.empty()) {
    Eigen::MatrixXd identity(n, static_cast<Eigen::Index>(model.identities.size()));
    for (size_t i = 0; i < model.identities.size(); ++i)
      identity.col(static_cast<Eigen::Index>(i)) = flatten(model.identities[i].offset);
    // An orthonormal basis of the identity modes; Q E = E - U (U^T E).
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(identity);
    const Eigen::MatrixXd u = qr.householderQ() * Eigen::MatrixXd::Identity(n, identity.cols());
    projected_ -= u * (u.transpose() * shapes);
  }
  gram_ = projected_.transpose() * projected_;
  gram_.diagonal().array() += options_.ridge * gram_.diagonal().mean();
  solver_.compute(gram_);
}

std::map<std::string, double> FaceModelFit::fit(const Positions& face) const {
  if (face.rows() * 3 != neutral_.size())
    throw Error("face fit",
                fmt::format("the face has {} vertices; the face model has {}", face.rows(), neutral_.size() / 3));
  // Q is symmetric and idempotent: (Q E)^T (face - neutral) = E^T Q d.
  const Eigen::VectorXd rhs = projected_.transpose() * (flatten(face) - neutral_);
  const Eigen::Index e = gram_.rows();
  // The unconstrained solution, clamped, is the start: exact when no bound is active.
  Eigen::VectorXd w = solver_.solve(rhs).cwiseMax(options_.lo).cwiseMin(options_.hi);
  for (int sweep = 0; sweep < options_.sweeps; ++sweep) {
    double largest = 0;
    for (Eigen::Index j = 0; j < e; ++j) {
      if (gram_(j, j) <= 0) continue;
      const double residual = rhs(j) - gram_.row(j).dot(w);
      const double next = std::clamp(w(j) + residual / gram_(j, j), options_.lo, options_.hi);
      largest = std::max(largest, std::abs(next - w(j)));
      w(j) = next;
    }
    if (largest <= options_.tolerance) break;
  }
  std::map<std::string, double> out;
  for (Eigen::Index j = 0; j < e; ++j) out[shapes_[static_cast<size_t>(j)]] = w(j);
  return out;
}

}  // namespace retarget
