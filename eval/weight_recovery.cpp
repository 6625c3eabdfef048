#include "eval/weight_recovery.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "core/error.h"
#include "core/random.h"
#include "geometry/dr_features.h"
#include "geometry/metrics.h"
#include "geometry/part_motion.h"
#include "geometry/reconstruction.h"
#include "geometry/rig_footprint.h"
#include "geometry/rig_weight_fit.h"

namespace retarget {

void WeightRecoveryOptions::validate() const {
  if (samples < 1) throw Error("weight_recovery.samples", "must be at least 1");
  if (!std::isfinite(ridge) || ridge < 0) throw Error("weight_recovery.ridge", "must be a finite number >= 0");
  if (!std::isfinite(still_mm) || still_mm <= 0) throw Error("weight_recovery.still_mm", "must be a finite number > 0");
}

WeightRecovery measure_weight_recovery(const Rig& rig, const WeightRecoveryOptions& options) {
  options.validate();
  const int C = rig.controller_count(), V = rig.neutral.vertex_count();
  if (C == 0) throw Error(rig.source, "the rig has no controllers: there are no weights to recover");
  WeightRecovery out;
  out.samples = options.samples;
  out.controllers = C;
  const bool eyes = !rig.eyes.left.empty() && !rig.eyes.right.empty();
  const double mm = eyes ? millimetres_per_unit(rig.neutral.vertices, rig.eyes) : 1.0;
  if (!eyes) out.unit = "units";

  // Still vertices as data/still_vertices.h finds them for a dataset: the rig's own footprint.
  ReconstructionOptions reconstruction;
  const Eigen::VectorXd motion = rig_footprint(rig, 0).motion;
  for (int v = 0; v < V; ++v)
    if (motion(v) * mm <= options.still_mm) reconstruction.anchors.push_back(v);
  out.still_vertices = static_cast<int>(reconstruction.anchors.size());
  reconstruction.align_to_rest = reconstruction.anchors.empty();
  if (options.part_motion)
    if (std::vector<std::vector<int>> parts = rig_parts_to_move(rig); !parts.empty())
      reconstruction.parts = std::make_shared<const PartMotion>(rig, std::move(parts));
  const Reconstruction rebuild(rig.neutral, reconstruction);
  const DrFeatures features(rig.neutral);
  RigWeightFitOptions fit_options;
  fit_options.ridge = options.ridge;
  const RigWeightFit fit(rig, fit_options);

  Random random(options.seed);
  for (int s = 0; s < options.samples; ++s) {
    Eigen::VectorXd w = Eigen::VectorXd::Zero(C);
    const int active = 1 + static_cast<int>(random.below(static_cast<uint64_t>(std::min(C, 5))));
    for (int k = 0; k < active; ++k) {
      const int c = static_cast<int>(random.below(static_cast<uint64_t>(C)));
      w(c) = random.uniform(rig.controllers[static_cast<size_t>(c)].min, rig.controllers[static_cast<size_t>(c)].max);
    }
    const Positions rebuilt = rebuild.reconstruct(features.compute(rig.evaluate(w)));
    const Eigen::VectorXd solved = fit.fit(rebuilt);
    out.mean_abs_error += (solved - w).cwiseAbs().mean();
    out.max_abs_error = std::max(out.max_abs_error, (solved - w).cwiseAbs().maxCoeff());
    out.residual += fit.residual(rebuilt, solved) * mm;
  }
  out.mean_abs_error /= options.samples;
  out.residual /= options.samples;
  return out;
}

}  // namespace retarget
