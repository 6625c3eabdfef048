#include "correspond/rig_head.h"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/log.h"
#include "correspond/annotation_evidence.h"
#include "correspond/annotation_project.h"
#include "correspond/belief_rounds.h"
#include "correspond/correspondence.h"
#include "correspond/rig_face_metric.h"
#include "data/dataset.h"
#include "data/test_faces.h"
#include "geometry/face_model.h"
#include "geometry/face_model_fit.h"
#include "geometry/mesh_io.h"

namespace retarget {

namespace fs = std::filesystem;

void RigHeadFitOptions::validate() const {
  if (correspondences.empty()) throw Error("--correspondences", "expected a correspondence folder");
  if (annotations.empty() && prior.empty())
    throw Error("--annotation", "expected an annotation project, a prior table (--prior), or both");
  map.validate("--prior-weight");
  if (belief && prior.empty()) throw Error("--belief", "the belief starts from a prior: give --prior");
  if (belief) belief_search.validate("--belief");
}

namespace {

// The face model a face-model dataset was built from; throws for a face folder.
FaceModel dataset_face_model(const Dataset& human) {
  if (human.recipes.empty())
    throw Error(human.folder, "was built from a face folder; the rig head fits a face model's blendshape weights");
  return load_face_model(human.source);
}

}  // namespace

ControllerMap fit_rig_head(const RigHeadFitOptions& options) {
  options.validate();
  const Correspondences c = load_correspondences(options.correspondences);
  const Dataset human = load_dataset(c.human_dataset), avatar = load_dataset(c.avatar_dataset);
  check_correspondences(c, human, avatar);
  if (human.recipes.empty())
    throw Error(human.folder, "has no expression recipes: the rig head learns from recipe weights");
  std::vector<std::string> shapes = blendshape_names(human.source);
  if (shapes.empty()) throw Error(human.source, "cannot read the face model's blendshape names");

  ControllerMap prior;
  if (!options.prior.empty()) prior = load_prior_map(options.prior, avatar.controllers, shapes);
  if (options.annotations.empty()) return prior;
  if (options.belief) {
    BeliefRounds rounds =
        belief_from_rounds(prior, load_dataset_rig(avatar), avatar, options.annotations, options.belief_search);
    rounds.belief.refine(options.belief_search.refine_passes);
    log::info("rig head: the map belief's most likely map (inside the ranges, sparse) after {} decided comparisons{}",
              rounds.comparisons,
              options.belief_search.refine_passes > 0
                  ? fmt::format(", {} passes of expectation propagation", options.belief_search.refine_passes)
                  : "");
    const std::vector<std::string> unreached = rounds.belief.unreached_controllers();
    if (!unreached.empty())
      log::warn(
          "rig head: no answer reached {} ({} of {} controllers: each entry of their rows is as unsure as before the "
          "rounds, often because the controller barely moves the face beside the rest of an expression): their rows "
          "are the prior table's, so confirm them in the table",
          fmt::join(unreached, ", "), unreached.size(), avatar.controllers.size());
    return rounds.belief.likely_map();
  }

  const std::vector<ExpressionRecipe> recipes = load_expression_recipes(human.recipes);
  const auto recipe_of = [&](const std::string& label) { return recipe_weights(recipes, label, human.recipes); };
  const AnnotationEvidence evidence = load_annotation_evidence(options.annotations, avatar, /*derived=*/true);
  const std::map<std::string, Eigen::VectorXd>& champions = evidence.champions;
  std::vector<RankedPair> comparisons;
  if (options.comparisons)
    for (const JudgedComparison& t : evidence.comparisons) comparisons.push_back({t.recipe, t.positive, t.negative});
  if (champions.empty() && comparisons.empty())
    throw Error(options.annotations.back(), "has no decided comparison yet: annotate a round first");
  std::vector<std::map<std::string, double>> pairs_human;
  Eigen::MatrixXd y(static_cast<Eigen::Index>(champions.size()), static_cast<Eigen::Index>(avatar.controllers.size()));
  for (const auto& [label, weights] : champions) {
    y.row(static_cast<Eigen::Index>(pairs_human.size())) = weights.transpose();
    pairs_human.push_back(recipe_of(label));
  }
  if (!options.comparisons)
    return fit_controller_map(pairs_human, y, avatar.controllers, shapes, options.prior.empty() ? nullptr : &prior,
                              options.map);
  if (options.prior.empty()) prior = controller_map_from_table({}, avatar.controllers, shapes);  // all zeros
  const Eigen::MatrixXd metric = rig_face_metric(load_dataset_rig(avatar), avatar);
  RankingOptions ranking = options.ranking;
  if (options.choose_prior_weight && !comparisons.empty()) {
    const PriorWeightChoice choice =
        choose_prior_weight(pairs_human, y, comparisons, metric, avatar.controllers, shapes, prior, ranking);
    std::string table;
    for (const auto& [weight, agreement] : choice.agreement) table += fmt::format(" {}: {:.3f};", weight, agreement);
    log::info("rig head: held-out agreement with the comparisons by prior weight:{} chose {}", table, choice.weight);
    if (!std::isfinite(choice.weight)) {
      prior.pairs = static_cast<int>(pairs_human.size());
      return prior;  // the annotators confirm the prior better than any correction of it
    }
    ranking.prior_weight = choice.weight;
  }
  return fit_controller_map_ranked(pairs_human, y, comparisons, metric, avatar.controllers, shapes, prior, ranking);
}

RigHeadApplyResult apply_rig_head(const ControllerMap& map, const std::string& faces_folder,
                                  const std::string& correspondences, const std::string& out) {
  const Correspondences c = load_correspondences(correspondences);
  const Dataset human = load_dataset(c.human_dataset), avatar = load_dataset(c.avatar_dataset);
  const TestFaces faces = load_test_faces(faces_folder);
  if (faces.fingerprint != human.fingerprint)
    throw Error(faces_folder, fmt::format("faces of topology {} but the human dataset {} has {}", faces.fingerprint,
                                          human.folder, human.fingerprint));
  const Rig rig = load_dataset_rig(avatar);
  map.on_rig({}, rig);  // the map's controllers are the rig's, before any face is read
  const FaceModelFit fit(dataset_face_model(human));
  fs::create_directories(out);
  RigHeadApplyResult result;
  result.weights_csv = (fs::path(out) / "weights.csv").string();
  std::string csv = "file";
  for (const std::string& name : map.controllers) csv += "," + name;
  csv += "\n";
  for (const TestFace& f : faces.faces) {
    const Mesh face = read_mesh((fs::path(faces_folder) / f.file).string());
    const Eigen::VectorXd w = map.on_rig(fit.fit(face.vertices), rig);
    write_mesh((fs::path(out) / (fs::path(f.file).stem().string() + ".obj")).string(),
               with_positions(rig.neutral, rig.evaluate(w)));
    csv += f.file;
    for (Eigen::Index i = 0; i < w.size(); ++i) csv += fmt::format(",{:.6g}", w(i));
    csv += "\n";
    ++result.faces;
  }
  write_file_atomically(result.weights_csv, [&](std::ostream& s) { s << csv; });
  log::info("rig head: {} faces onto {} through a map of {} pairs", result.faces, avatar.name, map.pairs);
  return result;
}

}  // namespace retarget
