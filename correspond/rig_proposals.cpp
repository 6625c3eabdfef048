#include "correspond/rig_proposals.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include "core/error.h"
#include "core/random.h"

namespace retarget {

namespace {

constexpr uint64_t kProposalStream = 300;  // mix_seed's stream for the groups' proposals

}  // namespace

void RigProposalOptions::validate(const std::string& key_path) const {
  if (count < 0) throw Error(key_path + ".count", fmt::format("expected 0 or more proposals, got {}", count));
  if (!std::isfinite(sigma) || sigma <= 0)
    throw Error(key_path + ".sigma", fmt::format("expected a finite step above 0 (a fraction of each controller's "
                                                 "range), got {}",
                                                 sigma));
  if (controllers < 1)
    throw Error(key_path + ".controllers", fmt::format("expected at least 1 controller moved, got {}", controllers));
}

torch::Tensor propose_rig_weights(const Rig& rig, const torch::Tensor& starts, const RigProposalOptions& options) {
  options.validate();
  const int64_t c = rig.controller_count();
  if (c == 0) throw Error(rig.source, "the rig has no controllers to propose expressions with");
  if (starts.dim() != 2 || starts.size(1) != c)
    throw Error(rig.source, fmt::format("proposals need start weights [K, {}] (one per controller), got {}", c,
                                        c10::str(starts.sizes())));
  const int64_t k = starts.size(0), m = options.count;
  const torch::Tensor s = starts.to(torch::kFloat64).contiguous();
  const auto start = s.accessor<double, 2>();
  for (int64_t i = 0; i < k; ++i)
    for (int64_t j = 0; j < c; ++j) {
      const Controller& ctl = rig.controllers[static_cast<size_t>(j)];
      const double slack = 1e-9 * std::max(1.0, ctl.max - ctl.min);
      if (!std::isfinite(start[i][j]) || start[i][j] < ctl.min - slack || start[i][j] > ctl.max + slack)
        throw Error(rig.source, fmt::format("start {} gives the controller \"{}\" the weight {}, outside its range "
                                            "[{}, {}]",
                                            i, ctl.name, start[i][j], ctl.min, ctl.max));
    }
  torch::Tensor out = torch::empty({k, m, c}, torch::kFloat64);
  auto w = out.accessor<double, 3>();
  const int moved = static_cast<int>(std::min<int64_t>(options.controllers, c));
  std::vector<int64_t> order(static_cast<size_t>(c));
  for (int64_t i = 0; i < k; ++i) {
    Random random(mix_seed(options.seed, kProposalStream, static_cast<uint64_t>(i)));
    for (int64_t p = 0; p < m; ++p) {
      for (int64_t j = 0; j < c; ++j) {
        const Controller& ctl = rig.controllers[static_cast<size_t>(j)];
        w[i][p][j] = std::clamp(start[i][j], ctl.min, ctl.max);
      }
      if (p == 0) continue;
      // `moved` distinct controllers: the first entries of a partial Fisher-Yates shuffle.
      std::iota(order.begin(), order.end(), int64_t{0});
      for (int t = 0; t < moved; ++t) {
        const int64_t pick = t + static_cast<int64_t>(random.below(static_cast<uint64_t>(c - t)));
        std::swap(order[static_cast<size_t>(t)], order[static_cast<size_t>(pick)]);
        const int64_t j = order[static_cast<size_t>(t)];
        const Controller& ctl = rig.controllers[static_cast<size_t>(j)];
        w[i][p][j] = std::clamp(w[i][p][j] + options.sigma * (ctl.max - ctl.min) * random.normal(), ctl.min, ctl.max);
      }
    }
  }
  return out;
}

}  // namespace retarget
