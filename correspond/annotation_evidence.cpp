#include "correspond/annotation_evidence.h"

#include <fmt/format.h>

#include "annotate/annotation_store.h"
#include "core/error.h"
#include "correspond/annotation_project.h"
#include "correspond/correspondence.h"
#include "geometry/face_model.h"

namespace retarget {

AnnotationEvidence load_annotation_evidence(const std::vector<std::string>& projects, const Dataset& avatar,
                                            bool derived) {
  AnnotationEvidence evidence;
  std::map<std::string, std::vector<ExpressionRecipe>> recipes_of;  // by recipes file, read once
  for (const std::string& folder : projects) {
    const AnnotationProject project = load_annotation_project(folder);
    const Correspondences round = load_correspondences(project.correspondences);
    if (round.avatar_fingerprint != avatar.fingerprint)
      throw Error(folder, fmt::format("its correspondences {} are over the avatar dataset {}, not {}",
                                      project.correspondences, round.avatar_dataset, avatar.folder));
    const auto weights_of = [&](int64_t id) {
      const torch::Tensor w = round.candidate_weights(avatar, id).to(torch::kFloat64).contiguous();
      return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(w.data_ptr<double>(), w.numel()));
    };
    const std::string recipes_file = dataset_recipes(round.human_dataset);
    if (!recipes_file.empty() && !recipes_of.count(recipes_file))
      recipes_of[recipes_file] = load_expression_recipes(recipes_file);
    const std::vector<ExpressionRecipe>& recipes = recipes_of[recipes_file];
    const auto recipe_of = [&](const std::string& label) {
      return recipes.empty() ? std::map<std::string, double>{} : recipe_weights(recipes, label, recipes_file);
    };
    AnnotationStore store = AnnotationStore::open(project.database());
    for (const GroupProgress& g : store.progress().groups)
      if (g.champion) evidence.champions[g.label] = weights_of(*g.champion);
    for (const Triplet& t : store.triplets(derived))
      evidence.comparisons.push_back(
          {t.anchor, weights_of(t.positive), weights_of(t.negative), t.tie_break, recipe_of(t.anchor), t.annotator});
  }
  return evidence;
}

}  // namespace retarget
