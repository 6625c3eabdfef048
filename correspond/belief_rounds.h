// Rounds chosen by the belief search (correspond/map_belief.h): the map belief after every
// decided comparison of the rounds so far (people's answers only: no tie-break, nothing
// inferred by transitivity), each expression's start (the controller weights the belief bets on)
// and next pair. `retarget correspond --informative` writes a round from it and
// `retarget rig-map fit --belief` its most likely map.
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

#include "correspond/map_belief.h"
#include "data/dataset.h"
#include "geometry/controller_map.h"
#include "geometry/rig.h"

namespace retarget {

struct BeliefRounds {
  MapBelief belief;
  Eigen::MatrixXd metric;  // C x C (correspond/rig_face_metric.h)
  int comparisons = 0;     // decided comparisons observed
};

// `prior`: the map the search starts from (load_prior_map: a controller table or map), over
// `rig`, the avatar dataset's rig, and the face model's shapes; `projects`: the earlier rounds,
// in order, each over any human dataset of the same face model (its groups read through that
// dataset's recipes: rounds over blends pool with rounds over the references). Throws
// retarget::Error naming the project for one over another avatar or a group without a recipe.
BeliefRounds belief_from_rounds(const ControllerMap& prior, const Rig& rig, const Dataset& avatar,
                                const std::vector<std::string>& projects, const BeliefSearchOptions& options);

}  // namespace retarget
