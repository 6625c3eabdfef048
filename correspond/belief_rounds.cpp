#include "correspond/belief_rounds.h"

#include <cmath>

#include "correspond/annotation_evidence.h"
#include "correspond/rig_face_metric.h"

namespace retarget {

namespace {

// What the prior says each controller stands for: the shapes its row of the map uses.
std::map<std::string, std::vector<std::string>> human_rows(const ControllerMap& map) {
  std::map<std::string, std::vector<std::string>> rows;
  for (Eigen::Index c = 0; c < map.matrix.rows(); ++c) {
    std::vector<std::string>& row = rows[map.controllers[static_cast<size_t>(c)]];
    for (Eigen::Index s = 0; s < map.matrix.cols(); ++s)
      if (std::abs(map.matrix(c, s)) > 1e-9) row.push_back(map.shapes[static_cast<size_t>(s)]);
  }
  return rows;
}

}  // namespace

BeliefRounds belief_from_rounds(const ControllerMap& prior, const Rig& rig, const Dataset& avatar,
                                const std::vector<std::string>& projects, const BeliefSearchOptions& options) {
  BeliefRounds rounds{MapBelief(prior, rig_lower(rig), rig_upper(rig), options),
                      rig_face_metric(rig, avatar, human_rows(prior)), 0};
  // Each comparison with its own round's recipe: rounds over blends and over the references pool.
  for (const JudgedComparison& t : load_annotation_evidence(projects, avatar, /*derived=*/false).comparisons) {
    if (t.tie_break) continue;
    rounds.belief.observe(rounds.belief.recipe_vector(t.recipe), rounds.metric, t.positive, t.negative, t.annotator);
    ++rounds.comparisons;
  }
  return rounds;
}

}  // namespace retarget
