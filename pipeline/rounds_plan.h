// How a budget of comparisons is spent in rounds (`retarget pipeline`'s method stages).
//
// belief (the default): each round asks one comparison per expression, the most informative
// pair under the belief every earlier answer updated; while the budget lasts a round asks about
// the references and the annotation dataset's random training blends beside them, then the last
// rounds ask about the references alone (the translation network F trains on those).
// champions / map: the paper's tournaments; a round of G groups of size s costs G * (s - 1)
// comparisons, s = min(16, left / G + 1), so later rounds shrink to fit the budget.
#pragma once

#include <string>
#include <vector>

namespace retarget {

struct RoundPlan {
  int number = 0;       // 1-based
  int group_size = 2;   // candidates per group
  bool blends = false;  // belief: asks about the annotation dataset (references and blends)
  int cost = 0;         // comparisons this round asks
};

// groups: the reference expressions; annotation_groups: those of the annotation dataset
// (references and blends; == groups when there is none). Throws retarget::Error("method.budget",
// ...) when the budget cannot pay one round, and for search other than belief, champions, map.
std::vector<RoundPlan> plan_rounds(int budget, const std::string& search, int groups, int annotation_groups);

// map search: the proposals' step around the rig head of the rounds before, shrinking by 0.7 a
// round from 0.4 (in controller range units).
double map_search_step(int round);

}  // namespace retarget
