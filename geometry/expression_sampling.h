// Random rig expressions for the avatar dataset, as in the paper: every sample activates a few
// controllers at random weights and leaves the others at rest.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/rig.h"

namespace retarget {

class ConfigNode;

struct SamplingOptions {
  int count = 2000;             // rows of the weight matrix (samples), including the neutral row; >= 1
  int min_active = 1;           // each sample activates k ~ uniform{min_active..max_active} distinct
  int max_active = 5;           //   controllers (both clamped to the rig's controller count); 1 <= min <= max
  uint64_t seed = 1;            // same seed, same weights, on every machine and compiler
  bool include_neutral = true;  // row 0 is the rest pose (every controller at rest)

  // Throws retarget::Error naming `key_path`.<field> for a value out of range.
  void validate(const std::string& key_path = "sampling") const;
};

// Reads the keys of SamplingOptions (count, min_active, max_active, seed, include_neutral) from
// a YAML map; unknown keys and bad values throw retarget::Error with file:line and key path.
SamplingOptions read_sampling_options(const ConfigNode& node);

// Rest weight of every controller: 0 clamped into its range [min, max] (0 for the usual
// [0, 1]; `min` for a range above 0, `max` for one below 0). #controllers.
Eigen::VectorXd rest_weights(const Rig& rig);

// count x #controllers rig weights. Row 0 is rest_weights(rig) when include_neutral. Every
// other row picks k ~ uniform{min_active..max_active} distinct controllers uniformly at random;
// each active controller c gets a weight ~ U(min_c, max_c] (never exactly min_c, so an active
// controller with range [0, 1] is never 0); inactive controllers keep their rest weight.
// Reproducible across machines and standard libraries: Random(options.seed) (core/random.h)
// draws k with below(), each pick with below(), each weight with uniform().
// Throws retarget::Error for invalid options or a rig without controllers.
Eigen::MatrixXd sample_rig_weights(const Rig& rig, const SamplingOptions& options);

// rig.evaluate() for every row of `weights` (count x #controllers), in parallel over rows.
// Returns count meshes' positions, each #V x 3 in the rig's units. Throws retarget::Error if
// weights.cols() differs from the controller count.
std::vector<Positions> evaluate_samples(const Rig& rig, const Eigen::MatrixXd& weights);

}  // namespace retarget
