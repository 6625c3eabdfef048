#include "geometry/rig_weight_fit.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace retarget {

void RigWeightFitOptions::validate() const {
  if (!(ridge >= 0) || !std::isfinite(ridge)) throw Error("rig_weight_fit.ridge", "expected a finite number >= 0");
  if (sweeps < 1) throw Error("rig_weight_fit.sweeps", "expected at least 1");
  if (!(tolerance > 0)) throw Error("rig_weight_fit.tolerance", "expected a positive number");
}

RigWeightFit::RigWeightFit(const Rig& rig, RigWeightFitOptions options) : rig_(rig), options_(options) {
  options_.validate();
  const int c = rig.controller_count();
  const int v = rig.neutral.vertex_count();
  basis_.resize(static_cast<Eigen::Index>(v) * 3, c);
  for (int k = 0; k < c; ++k) {
    const Positions& o = rig.controllers[k].offset;
    for (int i = 0; i < v; ++i)
      for (int a = 0; a < 3; ++a) basis_(i * 3 + a, k) = o(i, a);
  }
  gram_ = basis_.transpose() * basis_;
  if (c > 0 && options_.ridge > 0) gram_.diagonal().array() += options_.ridge * gram_.diagonal().mean();
}

Eigen::VectorXd RigWeightFit::fit(const Positions& deformed) const {
  const int c = rig_.controller_count();
  const int v = rig_.neutral.vertex_count();
  if (deformed.rows() != v)
    throw Error(rig_.source, fmt::format("a mesh of {} vertices cannot be fitted to the rig's {}", deformed.rows(), v));
  Eigen::VectorXd flat(static_cast<Eigen::Index>(v) * 3);
  for (int i = 0; i < v; ++i)
    for (int a = 0; a < 3; ++a) flat(i * 3 + a) = deformed(i, a) - rig_.neutral.vertices(i, a);
  const Eigen::VectorXd h = basis_.transpose() * flat;
  Eigen::VectorXd w = Eigen::VectorXd::Zero(c);
  for (int sweep = 0; sweep < options_.sweeps; ++sweep) {
    double change = 0;
    for (int k = 0; k < c; ++k) {
      if (gram_(k, k) <= 0) continue;  // a controller that moves nothing keeps weight 0
      const double step = (h(k) - gram_.row(k).dot(w)) / gram_(k, k);
      const double next = std::clamp(w(k) + step, rig_.controllers[k].min, rig_.controllers[k].max);
      change = std::max(change, std::abs(next - w(k)));
      w(k) = next;
    }
    if (change < options_.tolerance) break;
  }
  return w;
}

Positions RigWeightFit::project(const Positions& deformed) const { return rig_.evaluate(fit(deformed)); }

}  // namespace retarget
