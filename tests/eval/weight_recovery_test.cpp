// Rig weights recovered through the runtime's own path (DR features -> reconstruction -> fit), on
// the synthetic fox, whose controllers are independent enough for the 0.02.
#include "eval/weight_recovery.h"

#include <catch2/catch.hpp>

#include "scratch.h"
#include "synthetic/synthetic_faces.h"

namespace retarget {
namespace weight_recovery_test {

using Catch::Matchers::Contains;
using test::error_of;

TEST_CASE("the fox's own expressions give back their weights within 0.02 through reconstruction and the fit",
          "[eval][weights]") {
  const Rig fox = synthetic_avatars()[1].rig;
  REQUIRE(fox.name == "fox");
  WeightRecoveryOptions options;
  options.samples = 30;
  const WeightRecovery moving = measure_weight_recovery(fox, options);
  INFO("mean absolute weight error " << moving.mean_abs_error << ", residual " << moving.residual << " mm");
  CHECK(moving.unit == "mm");
  CHECK(moving.still_vertices > 0);
  CHECK(moving.mean_abs_error <= 0.02);
  // The same expressions (same seed) with the parts left at rest: never better.
  options.part_motion = false;
  const WeightRecovery still = measure_weight_recovery(fox, options);
  CHECK(still.residual >= moving.residual);
}

TEST_CASE("weight recovery refuses a rig without controllers and bad options", "[eval][weights]") {
  Rig fox = synthetic_avatars()[1].rig;
  WeightRecoveryOptions bad;
  bad.samples = 0;
  CHECK_THAT(error_of([&] { measure_weight_recovery(fox, bad); }), Contains("samples"));
  fox.controllers.clear();
  CHECK_THAT(error_of([&] { measure_weight_recovery(fox); }), Contains("no controllers"));
}

}  // namespace weight_recovery_test
}  // namespace retarget
