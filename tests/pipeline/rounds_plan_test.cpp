// How `retarget pipeline` spends a budget of comparisons in rounds (pipeline/rounds_plan.h), as
// scripts/method.sh did: the demo's 2,000 by belief search are 20 rounds of references and
// blends and 2 of references alone; the paper's tournaments shrink their last groups to fit.
#include "pipeline/rounds_plan.h"

#include <catch2/catch.hpp>

#include "scratch.h"

using namespace retarget;
using namespace retarget::test;

TEST_CASE("belief search: one pair per expression a round, blends while the budget lasts", "[pipeline]") {
  const std::vector<RoundPlan> rounds = plan_rounds(2000, "belief", 47, 94);
  REQUIRE(rounds.size() == 22);
  int spent = 0;
  for (const RoundPlan& r : rounds) {
    CHECK(r.group_size == 2);
    CHECK(r.cost == (r.blends ? 94 : 47));
    spent += r.cost;
  }
  CHECK(rounds[19].blends);
  CHECK_FALSE(rounds[20].blends);
  CHECK(rounds.back().number == 22);
  CHECK(spent == 20 * 94 + 2 * 47);
  CHECK(2000 - spent < 47);
  // Without an annotation dataset every round asks about the references.
  CHECK(plan_rounds(2000, "belief", 47, 47).size() == 42);
}

TEST_CASE("tournaments: groups of 16 while they fit, then smaller", "[pipeline]") {
  const std::vector<RoundPlan> rounds = plan_rounds(2000, "champions", 47, 47);
  REQUIRE(rounds.size() >= 3);
  CHECK(rounds[0].group_size == 16);
  CHECK(rounds[0].cost == 47 * 15);
  CHECK(rounds[1].group_size == 16);
  CHECK(rounds[2].group_size == (2000 - 2 * 705) / 47 + 1);
  int spent = 0;
  for (const RoundPlan& r : rounds) spent += r.cost;
  CHECK(spent <= 2000);
  CHECK(map_search_step(1) == Approx(0.4));
  CHECK(map_search_step(3) == Approx(0.4 * 0.49));
}

TEST_CASE("a budget that cannot pay one round is refused, naming the key", "[pipeline]") {
  CHECK(error_of([] { plan_rounds(40, "belief", 47, 94); }) ==
        "method.budget: a budget of 40 cannot pay one comparison per expression (47)");
  CHECK(error_of([] { plan_rounds(2000, "greedy", 47, 47); }) ==
        "method.search: expected belief, champions or map, got \"greedy\"");
}
