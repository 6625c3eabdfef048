#include "pipeline/round_starts.h"

#include <fmt/format.h>

#include <algorithm>

#include "annotate/annotation_store.h"
#include "core/error.h"
#include "correspond/annotation_project.h"
#include "correspond/belief_rounds.h"
#include "geometry/controller_map.h"
#include "geometry/face_model.h"

namespace retarget {

namespace {

// The earlier round's correspondences, checked to be over `avatar`.
Correspondences earlier_round(const std::string& around, const AnnotationProject& project, const Dataset& avatar) {
  Correspondences earlier = load_correspondences(project.correspondences);
  if (earlier.avatar_fingerprint != avatar.fingerprint || earlier.avatar_name != avatar.name)
    throw Error(around, fmt::format("its tournaments are over the avatar dataset \"{}\" (topology {}), not \"{}\" "
                                    "(topology {}) given with --avatar",
                                    earlier.avatar_name, earlier.avatar_fingerprint, avatar.name, avatar.fingerprint));
  if (earlier.avatar_samples != avatar.sample_count())
    throw Error(around, fmt::format("its correspondences were built on {} avatar samples, the avatar dataset {} has {}",
                                    earlier.avatar_samples, avatar.folder, avatar.sample_count()));
  return earlier;
}

// The champion of `name`'s tournament (an index into the earlier correspondences' candidates).
int64_t champion(const std::string& around, const StoreProgress& progress, const std::string& name,
                 const Correspondences& earlier) {
  const auto group = std::find_if(progress.groups.begin(), progress.groups.end(),
                                  [&](const GroupProgress& g) { return g.label == name; });
  if (group == progress.groups.end()) throw Error(around, "has no tournament for the expression \"" + name + "\"");
  if (!group->champion)
    throw Error(around, fmt::format("the tournament of \"{}\" is not finished ({} of {} comparisons decided); "
                                    "finish it first (retarget annotate simulate, terminal or serve)",
                                    name, group->done, group->total));
  if (*group->champion < 0 || *group->champion >= earlier.candidate_count())
    throw Error(around, fmt::format("the champion of \"{}\" is sample {}, outside its correspondences' {} candidates",
                                    name, *group->champion, earlier.candidate_count()));
  return *group->champion;
}

}  // namespace

RoundStartRule champions_of(const std::string& around) {
  return [around](const RoundStartInputs& in) {
    const AnnotationProject project = load_annotation_project(around);
    const Correspondences earlier = earlier_round(around, project, in.avatar);
    const StoreProgress progress = AnnotationStore::open(project.database()).progress();
    std::vector<torch::Tensor> weights, features;
    for (const std::string& name : in.names) {
      const int64_t id = champion(around, progress, name, earlier);
      weights.push_back(earlier.candidate_weights(in.avatar, id));
      features.push_back(earlier.candidate_features(in.avatar, id));
    }
    RoundStarts starts;
    starts.weights = torch::stack(weights).contiguous();
    starts.features = torch::stack(features).contiguous();
    starts.evidence_comparisons = progress.done();
    return starts;
  };
}

RoundStartRule belief_search_round(const std::string& start_table, const std::vector<std::string>& evidence,
                                   const BeliefSearchOptions& options) {
  options.validate("correspond.belief");
  return [start_table, evidence, options](const RoundStartInputs& in) {
    if (in.human.recipes.empty())
      throw Error("correspond.informative",
                  in.human.folder + " has no expression recipes for the belief's map to read");
    const std::vector<std::string> shapes = blendshape_names(in.human.source);
    if (shapes.empty()) throw Error(in.human.source, "cannot read the face model's blendshape names");
    const BeliefRounds rounds = belief_from_rounds(load_prior_map(start_table, in.avatar.controllers, shapes), in.rig,
                                                   in.avatar, evidence, options);
    const std::vector<ExpressionRecipe> recipes = load_expression_recipes(in.human.recipes);
    const auto k = static_cast<int64_t>(in.names.size());
    const int64_t c = in.rig.controller_count();
    RoundStarts starts;
    starts.weights = torch::empty({k, c}, torch::kFloat64);
    starts.pairs = torch::empty({k, 2, c}, torch::kFloat64);
    for (int64_t i = 0; i < k; ++i) {
      const Eigen::VectorXd r =
          rounds.belief.recipe_vector(recipe_weights(recipes, in.names[static_cast<size_t>(i)], in.human.recipes));
      const Eigen::VectorXd w =
          belief_estimate(rounds.belief.expression(r), rounds.belief.lower(), rounds.belief.upper());
      const auto pair = rounds.belief.next_pair(r, rounds.metric);
      for (int64_t j = 0; j < c; ++j) {
        starts.weights[i][j] = w(j);
        starts.pairs[i][0][j] = pair[0](j);
        starts.pairs[i][1][j] = pair[1](j);
      }
    }
    starts.evidence_comparisons = rounds.comparisons;
    return starts;
  };
}

}  // namespace retarget
