#include "geometry/expression_blends.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/config.h"
#include "core/error.h"
#include "core/random.h"

namespace retarget {

void BlendOptions::validate(const std::string& key_path) const {
  require(count >= 0 && count <= kMaxBlends, key_path + ".count",
          fmt::format("expected 0 to {} blends (--blends), got {}", kMaxBlends, count));
  require(min_shapes >= 1, key_path + ".min_shapes", fmt::format("expected at least 1, got {}", min_shapes));
  require(max_shapes >= min_shapes, key_path + ".max_shapes",
          fmt::format("expected at least min_shapes ({}), got {}", min_shapes, max_shapes));
  require(std::isfinite(min_weight) && min_weight > 0, key_path + ".min_weight",
          fmt::format("expected a weight > 0, got {}", min_weight));
  require(std::isfinite(max_weight) && max_weight >= min_weight && max_weight <= 10, key_path + ".max_weight",
          fmt::format("expected a weight in [min_weight ({}), 10], got {}", min_weight, max_weight));
  require(!prefix.empty(), key_path + ".prefix", "expected a non-empty name prefix");
}

namespace {

// True when `blend` names the same shapes as `recipe` (weights above 0.05) within 0.05 each.
bool looks_like(const std::map<std::string, double>& blend, const ExpressionRecipe& recipe) {
  constexpr double kClose = 0.05;
  std::map<std::string, double> all = recipe.weights;
  for (const auto& [name, w] : blend) all.emplace(name, 0.0);
  for (const auto& [name, w] : all) {
    const auto b = blend.find(name);
    const auto r = recipe.weights.find(name);
    const double bw = b == blend.end() ? 0 : b->second, rw = r == recipe.weights.end() ? 0 : r->second;
    if (std::abs(bw - rw) > kClose) return false;
  }
  return true;
}

}  // namespace

std::vector<ExpressionRecipe> random_blends(const std::vector<std::string>& shapes, const BlendOptions& options,
                                            const std::vector<ExpressionRecipe>& avoid) {
  options.validate();
  if (options.count > 0 && shapes.empty()) throw Error("blends", "the face model has no expression shapes to blend");
  Random random(options.seed);
  const int n = static_cast<int>(shapes.size());
  const int lo = std::min(options.min_shapes, n), hi = std::min(options.max_shapes, n);
  std::vector<ExpressionRecipe> blends;
  int redraws = 0;
  while (static_cast<int>(blends.size()) < options.count) {
    const int k = lo + static_cast<int>(random.below(static_cast<uint64_t>(hi - lo + 1)));
    std::vector<int> order(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) order[static_cast<size_t>(i)] = i;
    ExpressionRecipe blend;
    blend.name = fmt::format("{}{:03d}", options.prefix, blends.size());
    for (int j = 0; j < k; ++j) {  // a partial Fisher-Yates: k distinct shapes
      const int pick = j + static_cast<int>(random.below(static_cast<uint64_t>(n - j)));
      std::swap(order[static_cast<size_t>(j)], order[static_cast<size_t>(pick)]);
      blend.weights[shapes[static_cast<size_t>(order[static_cast<size_t>(j)])]] =
          random.uniform(options.min_weight, options.max_weight);
    }
    const bool reference = std::any_of(avoid.begin(), avoid.end(),
                                       [&](const ExpressionRecipe& r) { return looks_like(blend.weights, r); });
    if (reference && ++redraws < 1000 * (options.count + 1)) continue;
    blends.push_back(std::move(blend));
  }
  return blends;
}

}  // namespace retarget
