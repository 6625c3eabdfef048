#include "correspond/rig_proposals.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "core/error.h"
#include "test_support.h"

using Catch::Contains;
using namespace retarget;

namespace {

// Four controllers with different ranges: proposals must respect each one's own range.
Rig ranged_rig() {
  Rig rig;
  rig.name = "ranged";
  rig.source = "ranged.yaml";
  rig.neutral = quad_grid(3, 3, 1.0, 1.0);
  const double ranges[4][2] = {{0, 1}, {-1, 1}, {0, 2}, {-0.5, 0}};
  for (int c = 0; c < 4; ++c) {
    Controller controller;
    controller.name = "c" + std::to_string(c);
    controller.offset = Positions::Zero(rig.neutral.vertex_count(), 3);
    controller.min = ranges[c][0];
    controller.max = ranges[c][1];
    rig.controllers.push_back(controller);
  }
  return rig;
}

torch::Tensor starts() {
  return torch::tensor({0.5, 0.0, 1.0, -0.25, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, -0.5}, torch::kFloat64)
      .reshape({3, 4});
}

}  // namespace

TEST_CASE("rig proposals: the start first, then moves of a few controllers inside their ranges", "[proposals]") {
  const Rig rig = ranged_rig();
  RigProposalOptions o;
  o.count = 40;
  o.controllers = 2;
  const torch::Tensor s = starts();
  const torch::Tensor w = propose_rig_weights(rig, s, o);
  REQUIRE(w.sizes() == c10::IntArrayRef({3, 40, 4}));
  REQUIRE(w.scalar_type() == torch::kFloat64);
  int moved_some = 0;
  for (int64_t k = 0; k < 3; ++k) {
    CHECK(torch::equal(w[k][0], s[k]));
    for (int64_t p = 1; p < 40; ++p) {
      int changed = 0;
      for (int64_t c = 0; c < 4; ++c) {
        const double x = w[k][p][c].item<double>();
        CHECK(x >= rig.controllers[c].min);
        CHECK(x <= rig.controllers[c].max);
        changed += x != s[k][c].item<double>();
      }
      CHECK(changed <= 2);
      moved_some += changed > 0;
    }
  }
  // Only clamps at range ends keep a proposal on its start (group 2 starts at three range ends).
  CHECK(moved_some >= 3 * 39 * 7 / 10);
}

TEST_CASE("rig proposals: reproducible, seed-dependent, one stream per group", "[proposals]") {
  const Rig rig = ranged_rig();
  RigProposalOptions o;
  o.count = 6;
  const torch::Tensor s = starts();
  const torch::Tensor a = propose_rig_weights(rig, s, o);
  CHECK(torch::equal(a, propose_rig_weights(rig, s, o)));
  o.seed = 2;
  const torch::Tensor b = propose_rig_weights(rig, s, o);
  CHECK(!torch::equal(a.slice(1, 1), b.slice(1, 1)));
  CHECK(torch::equal(a.select(1, 0), b.select(1, 0)));  // the start stays first whatever the seed
  // Another start for group 0 leaves group 1's moves (which controllers, by how much) alone.
  o.seed = 1;
  torch::Tensor other = s.clone();
  other[0][0] = 0.9;
  const torch::Tensor c = propose_rig_weights(rig, other, o);
  CHECK(torch::equal(c[1], a[1]));
  CHECK(!torch::equal(c[0], a[0]));
}

TEST_CASE("rig proposals: steps are normal with sigma times the controller's range", "[proposals]") {
  Rig rig = ranged_rig();
  RigProposalOptions o;
  o.count = 4001;
  o.controllers = 1;
  o.sigma = 0.05;
  // Starts in the middle of each range, far (10 sigma) from its ends: no clamping.
  const torch::Tensor s = torch::tensor({0.5, 0.0, 1.0, -0.25}, torch::kFloat64).reshape({1, 4});
  const torch::Tensor w = propose_rig_weights(rig, s, o)[0].slice(0, 1);  // [4000, 4]
  const torch::Tensor steps = w - s;
  for (int64_t c = 0; c < 4; ++c) {
    INFO("controller " << c);
    const double range = rig.controllers[c].max - rig.controllers[c].min;
    const torch::Tensor moved = steps.select(1, c).index({steps.select(1, c) != 0});
    // Each proposal moves one controller chosen uniformly: about 1000 each.
    CHECK(moved.numel() > 850);
    CHECK(moved.numel() < 1150);
    const double sd = moved.std().item<double>() / range;
    CHECK(sd == Approx(0.05).epsilon(0.08));
    CHECK(std::abs(moved.mean().item<double>() / range) < 0.01);
  }
}

TEST_CASE("rig proposals: bad options and starts are named", "[proposals]") {
  const Rig rig = ranged_rig();
  RigProposalOptions o;
  o.count = 4;
  o.sigma = 0;
  CHECK_THROWS_WITH(propose_rig_weights(rig, starts(), o), Contains("correspond.proposals.sigma"));
  o.sigma = 0.4;
  o.controllers = 0;
  CHECK_THROWS_WITH(propose_rig_weights(rig, starts(), o), Contains("correspond.proposals.controllers"));
  o.controllers = 2;
  o.count = -1;
  CHECK_THROWS_WITH(propose_rig_weights(rig, starts(), o), Contains("correspond.proposals.count"));
  o.count = 4;
  CHECK_THROWS_WITH(propose_rig_weights(rig, torch::zeros({2, 3}, torch::kFloat64), o),
                    Contains("ranged.yaml") && Contains("[K, 4]"));
  torch::Tensor outside = starts();
  outside[2][3] = 0.5;  // c3's range is [-0.5, 0]
  CHECK_THROWS_WITH(propose_rig_weights(rig, outside, o), Contains("\"c3\"") && Contains("outside its range"));
}
