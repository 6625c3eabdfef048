#include "pipeline/rounds_plan.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace retarget {

std::vector<RoundPlan> plan_rounds(int budget, const std::string& search, int groups, int annotation_groups) {
  if (search != "belief" && search != "champions" && search != "map")
    throw Error("method.search", "expected belief, champions or map, got \"" + search + "\"");
  if (groups <= 0) throw Error("human.recipes", "holds no expression recipes");
  std::vector<RoundPlan> rounds;
  int left = budget;
  while (left >= groups) {
    RoundPlan r;
    r.number = static_cast<int>(rounds.size()) + 1;
    if (search == "belief") {
      r.blends = annotation_groups > groups && left - annotation_groups >= groups;
      r.cost = r.blends ? annotation_groups : groups;
    } else {
      r.group_size = std::min(left / groups + 1, 16);
      r.cost = groups * (r.group_size - 1);
    }
    left -= r.cost;
    rounds.push_back(r);
  }
  if (rounds.empty())
    throw Error("method.budget",
                fmt::format("a budget of {} cannot pay one comparison per expression ({})", budget, groups));
  return rounds;
}

double map_search_step(int round) { return 0.4 * std::pow(0.7, round - 1); }

}  // namespace retarget
