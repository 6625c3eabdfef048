// Where a round of comparisons starts each expression, from the rounds before it: the
// orchestration of rounds that `retarget correspond --around / --informative` and the pipeline's
// round stages use. Correspondences (correspond/correspondence.h) stay a library: they take these
// as a RoundStartRule and call it once their inputs are loaded.
#pragma once

#include <string>
#include <vector>

#include "correspond/belief_search.h"
#include "correspond/correspondence.h"

namespace retarget {

// The paper's tournaments: each expression starts at the champion of its tournament in the
// annotation project `project` (a dataset sample or one of its correspondences' proposals),
// whose correspondences must be over the same avatar dataset. The rule throws retarget::Error
// naming the project for a missing group, an unfinished tournament or another avatar.
RoundStartRule champions_of(const std::string& project);

// The belief search: each expression starts at what the map belief bets on (its most likely rig
// weights inside the ranges) and asks the pair with the most expected information, the belief
// starting at the controller table or map `start_table` and having observed every decided
// comparison of the `evidence` projects (the earlier rounds, in order; correspond/belief_rounds.h).
// The rule throws retarget::Error when the human dataset has no recipes or face model names.
RoundStartRule belief_search_round(const std::string& start_table, const std::vector<std::string>& evidence,
                                   const BeliefSearchOptions& options);

}  // namespace retarget
