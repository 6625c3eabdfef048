#include "geometry/expression_sampling.h"

#include <algorithm>
#include <numeric>

#include "core/config.h"
#include "core/error.h"
#include "core/random.h"

namespace retarget {

void SamplingOptions::validate(const std::string& key_path_prefix) const {
  require(count >= 1, key_path(key_path_prefix, "count"), "expected at least 1 sample, got " + std::to_string(count));
  require(min_active >= 1, key_path(key_path_prefix, "min_active"),
          "expected at least 1 active controller, got " + std::to_string(min_active));
  require(max_active >= min_active, key_path(key_path_prefix, "max_active"),
          "expected a number >= min_active (" + std::to_string(min_active) + "), got " + std::to_string(max_active));
}

SamplingOptions read_sampling_options(const ConfigNode& node) {
  node.reject_unknown_keys({"count", "min_active", "max_active", "seed", "include_neutral"});
  SamplingOptions options;
  node.get("count", options.count);
  node.get("min_active", options.min_active);
  node.get("max_active", options.max_active);
  if (node.has("seed")) {
    const int64_t seed = node.child("seed").as<int64_t>();
    if (seed < 0) node.child("seed").fail("expected a seed >= 0, got " + std::to_string(seed));
    options.seed = static_cast<uint64_t>(seed);
  }
  node.get("include_neutral", options.include_neutral);
  options.validate(node.path());
  return options;
}

Eigen::VectorXd rest_weights(const Rig& rig) {
  Eigen::VectorXd rest(rig.controller_count());
  for (int c = 0; c < rig.controller_count(); ++c)
    rest[c] = std::clamp(0.0, rig.controllers[c].min, rig.controllers[c].max);
  return rest;
}

Eigen::MatrixXd sample_rig_weights(const Rig& rig, const SamplingOptions& options) {
  options.validate();
  const int controllers = rig.controller_count();
  if (controllers == 0) throw Error(rig.source.empty() ? "rig" : rig.source, "the rig has no controllers to sample");
  const int lo = std::min(options.min_active, controllers);
  const int hi = std::min(options.max_active, controllers);

  const Eigen::VectorXd rest = rest_weights(rig);
  Eigen::MatrixXd weights = rest.transpose().replicate(options.count, 1);
  Random random(options.seed);
  std::vector<int> order(controllers);
  for (int row = options.include_neutral ? 1 : 0; row < options.count; ++row) {
    const int k = lo + static_cast<int>(random.below(static_cast<uint64_t>(hi - lo + 1)));
    // Partial Fisher-Yates from the identity order: the first k entries are k distinct
    // controllers, every k-subset equally likely.
    std::iota(order.begin(), order.end(), 0);
    for (int j = 0; j < k; ++j) {
      const int pick = j + static_cast<int>(random.below(static_cast<uint64_t>(controllers - j)));
      std::swap(order[j], order[pick]);
      const Controller& controller = rig.controllers[order[j]];
      weights(row, order[j]) = random.uniform(controller.min, controller.max);
    }
  }
  return weights;
}

std::vector<Positions> evaluate_samples(const Rig& rig, const Eigen::MatrixXd& weights) {
  if (weights.cols() != rig.controller_count())
    throw Error(rig.source.empty() ? "rig" : rig.source, "the weights have " + std::to_string(weights.cols()) +
                                                             " columns but the rig has " +
                                                             std::to_string(rig.controller_count()) + " controllers");
  std::vector<Positions> samples(weights.rows());
  const int rows = static_cast<int>(weights.rows());
#pragma omp parallel for schedule(static)
  for (int row = 0; row < rows; ++row) samples[row] = rig.evaluate(weights.row(row).transpose());
  return samples;
}

}  // namespace retarget
