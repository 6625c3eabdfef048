#include "geometry/rig_weight_fit.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "geometry/rig_footprint.h"

namespace retarget {

void RigWeightFitOptions::validate() const {
  if (!(ridge >= 0) || !std::isfinite(ridge)) throw Error("rig_weight_fit.ridge", "expected a finite number >= 0");
  if (!(smoothness >= 0) || !std::isfinite(smoothness))
    throw Error("rig_weight_fit.smoothness", "expected a finite number >= 0");
  if (sweeps < 1) throw Error("rig_weight_fit.sweeps", "expected at least 1");
  if (!(tolerance > 0)) throw Error("rig_weight_fit.tolerance", "expected a positive number");
}

RigWeightFit::RigWeightFit(const Rig& rig, RigWeightFitOptions options) : rig_(rig), options_(options) {
  options_.validate();
  const int c = rig.controller_count();
  const int v = rig.neutral.vertex_count();
  basis_.resize(static_cast<Eigen::Index>(v) * 3, c);
  Eigen::VectorXd motion = Eigen::VectorXd::Zero(v);
  for (int k = 0; k < c; ++k) {
    const Controller& controller = rig.controllers[k];
    const Positions& o = controller.offset;
    const double reach = std::max(std::abs(controller.min), std::abs(controller.max));
    for (int i = 0; i < v; ++i) {
      for (int a = 0; a < 3; ++a) basis_(i * 3 + a, k) = o(i, a);
      motion(i) = std::max(motion(i), o.row(i).norm() * reach);
    }
  }
  gram_ = basis_.transpose() * basis_;
  scale_ = c > 0 ? gram_.diagonal().mean() : 0;
  if (c > 0 && options_.ridge > 0) gram_.diagonal().array() += options_.ridge * scale_;
  const Positions& n = rig.neutral.vertices;
  basis_neutral_ = basis_.transpose() * Eigen::Map<const Eigen::VectorXd>(n.data(), n.size());
  moving_ = retarget::moving_vertices(motion, 0.0, 0.01);
}

void RigWeightFit::check_vertices(const Positions& deformed) const {
  const int v = rig_.neutral.vertex_count();
  if (deformed.rows() != v)
    throw Error(rig_.source, fmt::format("a mesh of {} vertices cannot be fitted to the rig's {}", deformed.rows(), v));
}

Eigen::VectorXd RigWeightFit::fit(const Positions& deformed) const { return fit(deformed, Eigen::VectorXd()); }

Eigen::VectorXd RigWeightFit::fit(const Positions& deformed, const Eigen::VectorXd& previous) const {
  const int c = rig_.controller_count();
  check_vertices(deformed);
  if (previous.size() != 0 && previous.size() != c)
    throw Error(rig_.source, fmt::format("{} previous weights for a rig of {} controllers", previous.size(), c));
  // basis^T (deformed - neutral), without the 3V difference (Positions is row-major: row 3v + a).
  Eigen::VectorXd h = basis_.transpose() * Eigen::Map<const Eigen::VectorXd>(deformed.data(), deformed.size());
  h -= basis_neutral_;
  // The smoothness term adds s I to the normal equations' matrix and s w_previous to the right.
  const bool smooth = previous.size() == c && options_.smoothness > 0;
  const double s = smooth ? options_.smoothness * scale_ : 0;
  if (smooth) h += s * previous;
  Eigen::VectorXd w = Eigen::VectorXd::Zero(c);
  if (previous.size() == c)
    for (int k = 0; k < c; ++k) w(k) = std::clamp(previous(k), rig_.controllers[k].min, rig_.controllers[k].max);
  for (int sweep = 0; sweep < options_.sweeps; ++sweep) {
    double change = 0;
    for (int k = 0; k < c; ++k) {
      const double diagonal = gram_(k, k) + s;
      if (gram_(k, k) <= 0) {  // a controller that moves nothing keeps weight 0
        w(k) = std::clamp(0.0, rig_.controllers[k].min, rig_.controllers[k].max);
        continue;
      }
      const double step = (h(k) - gram_.row(k).dot(w) - s * w(k)) / diagonal;
      const double next = std::clamp(w(k) + step, rig_.controllers[k].min, rig_.controllers[k].max);
      change = std::max(change, std::abs(next - w(k)));
      w(k) = next;
    }
    if (change < options_.tolerance) break;
  }
  return w;
}

Positions RigWeightFit::project(const Positions& deformed) const { return rig_.evaluate(fit(deformed)); }

double RigWeightFit::residual(const Positions& deformed, const Eigen::VectorXd& weights) const {
  check_vertices(deformed);
  const int c = rig_.controller_count();
  if (weights.size() != c)
    throw Error(rig_.source, fmt::format("{} weights for a rig of {} controllers", weights.size(), c));
  if (moving_.empty()) return 0;
  const Positions& n = rig_.neutral.vertices;
  double sum = 0;
  for (const int i : moving_) {
    Eigen::Vector3d r = (deformed.row(i) - n.row(i)).transpose();
    for (int a = 0; a < 3; ++a) r(a) -= basis_.row(i * 3 + a).dot(weights);
    sum += r.norm();
  }
  return sum / static_cast<double>(moving_.size());
}

}  // namespace retarget
