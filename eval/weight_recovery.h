// How well a rig's weights come back through the runtime's own path, before any network: the
// rig's own expressions (1-5 controllers at uniform weights in their ranges, as avatar datasets
// sample them) as DR features, rebuilt by the reconstruction the bundle uses (still vertices
// anchored, rigid parts following the rig), then solved for weights with the ridge
// `retarget-infer --weights` uses. The error is a floor: what `--weights` cannot beat on this rig
// even with a perfect network.
#pragma once

#include <cstdint>
#include <string>

#include "geometry/rig.h"

namespace retarget {

struct WeightRecoveryOptions {
  int samples = 100;        // expressions, >= 1
  uint64_t seed = 1;        // same seed, same expressions on every machine (core/random.h)
  double ridge = 1e-4;      // RigWeightFitOptions::ridge, >= 0
  bool part_motion = true;  // rigid parts follow the rig (geometry/part_motion.h)
  double still_mm = 0.01;   // vertices no controller moves further than this are anchored, > 0
  void validate() const;    // throws retarget::Error naming the field
};

struct WeightRecovery {
  int samples = 0, controllers = 0, still_vertices = 0;
  double mean_abs_error = 0;  // mean over samples and controllers of |solved - true| weight
  double max_abs_error = 0;   // the largest of any controller in any sample
  double residual = 0;        // mean RigWeightFit::residual, in `unit`
  std::string unit = "mm";    // "mm" (the rig's eyes: 10 cm apart), or "units" without eyes
};

// Throws retarget::Error for bad options or a rig without controllers.
WeightRecovery measure_weight_recovery(const Rig& rig, const WeightRecoveryOptions& options = {});

}  // namespace retarget
