// Rounds chosen by the belief search (correspond/map_belief.h): the map belief after every
// decided comparison of the rounds so far (people's answers only: no tie-break, nothing
// inferred by transitivity), each expression's start (the controller weights the belief bets on)
// and next pair. `retarget correspond --informative` writes a round from it and
// `retarget rig-map fit --belief` its mean map.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "correspond/annotation_evidence.h"
#include "correspond/map_belief.h"
#include "data/dataset.h"
#include "geometry/face_model.h"

namespace retarget {

struct BeliefRounds {
  MapBelief belief;
  Eigen::MatrixXd metric;                  // C x C (correspond/rig_face_metric.h)
  int comparisons = 0;                     // decided comparisons observed
  std::vector<JudgedComparison> held_out;  // those of the held-out expressions, not observed
};

// `prior`: the controller table or controller map (geometry/controller_map.h) the search starts
// from, over the avatar dataset's rig and the human dataset's face model; `projects`: the
// earlier rounds, in order, each over any human dataset of the same face model (its groups read
// through that dataset's recipes: rounds over blends pool with rounds over the references).
// Throws retarget::Error naming the file for a prior that does not fit, a project over another
// avatar, or a group without a recipe. The comparisons of the expressions named in `held_out`
// are kept aside, not observed.
BeliefRounds belief_from_rounds(const std::string& prior, const Dataset& human, const Dataset& avatar,
                                const std::vector<std::string>& projects, const BeliefSearchOptions& options,
                                const std::set<std::string>& held_out = {});

// Whether the annotators taught anything the prior did not already say, by their own answers:
// the expressions are dealt into `folds` folds; for each, the belief learnt from the others'
// comparisons and the prior alone each predict the held-out comparisons (the weights each bets
// on lie nearer the chosen face than the other, in the face metric). A prior that people agree
// with as well as with what they taught elsewhere is worth keeping: a reading that the
// annotators share but that is not the avatar's (the fox) then does not replace a right prior.
struct PriorCheck {
  double belief = 0, prior = 0;  // the fraction of held-out comparisons each agrees with
  int comparisons = 0;           // held-out comparisons
  // The belief is better than the prior by more than the comparisons' own noise (one standard
  // error of the belief's agreement).
  bool belief_wins() const {
    return comparisons > 0 && belief - prior > std::sqrt(belief * (1 - belief) / comparisons);
  }
};
PriorCheck check_against_prior(const std::string& prior, const Dataset& human, const Dataset& avatar,
                               const std::vector<std::string>& projects, const BeliefSearchOptions& options,
                               int folds = 4);

}  // namespace retarget
