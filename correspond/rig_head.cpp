#include "correspond/rig_head.h"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>

#include "annotate/annotation_store.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/log.h"
#include "correspond/annotation_project.h"
#include "correspond/correspondence.h"
#include "data/dataset.h"
#include "data/test_faces.h"
#include "geometry/face_model.h"
#include "geometry/face_model_fit.h"
#include "geometry/mesh_io.h"
#include "geometry/metrics.h"
#include "geometry/rig_footprint.h"

namespace retarget {

namespace fs = std::filesystem;

void RigHeadFitOptions::validate() const {
  if (correspondences.empty()) throw Error("--correspondences", "expected a correspondence folder");
  if (annotations.empty() && prior.empty())
    throw Error("--annotation", "expected an annotation project, a prior table (--prior), or both");
  map.validate("--prior-weight");
}

namespace {

// The face model a face-model dataset was built from; throws for a face folder.
FaceModel dataset_face_model(const Dataset& human) {
  if (human.recipes.empty())
    throw Error(human.folder, "was built from a face folder; the rig head fits a face model's blendshape weights");
  return load_face_model(human.source);
}

// C x C: the Gram matrix of the rig's offsets over the vertices it moves, scaled to a mean
// diagonal of 1, so that |w - v|^2_G measures how far apart the faces of w and v are (not the
// weights), in units comparable to squared weights.
Eigen::MatrixXd face_metric(const Rig& rig, const Dataset& avatar) {
  const double mm = avatar.eyes.left.empty() ? 1.0 : millimetres_per_unit(rig.neutral.vertices, avatar.eyes);
  const RigFootprint footprint = rig_footprint(rig, 0.1 / mm);
  const Eigen::Index c = rig.controller_count();
  Eigen::MatrixXd b(static_cast<Eigen::Index>(footprint.moving.size()) * 3, c);
  for (Eigen::Index j = 0; j < c; ++j)
    for (size_t i = 0; i < footprint.moving.size(); ++i)
      b.block<3, 1>(static_cast<Eigen::Index>(3 * i), j) =
          rig.controllers[static_cast<size_t>(j)].offset.row(footprint.moving[i]).transpose();
  Eigen::MatrixXd g = b.transpose() * b;
  const double scale = g.diagonal().mean();
  return scale > 0 ? Eigen::MatrixXd(g / scale) : Eigen::MatrixXd::Identity(c, c);
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
  if (!options.prior.empty()) {
    const ControllerCorrespondence table = load_controller_correspondence(options.prior);
    check_controller_correspondence(table, avatar.controllers, shapes, options.prior);
    prior = controller_map_from_table(table, avatar.controllers, shapes);
    prior.prior = fs::absolute(options.prior).lexically_normal().string();
  }
  if (options.annotations.empty()) return prior;

  const std::vector<ExpressionRecipe> recipes = load_expression_recipes(human.recipes);
  const auto recipe_of = [&](const std::string& label) -> const std::map<std::string, double>& {
    const auto recipe =
        std::find_if(recipes.begin(), recipes.end(), [&](const ExpressionRecipe& r) { return r.name == label; });
    if (recipe == recipes.end()) throw Error(human.recipes, "has no recipe for the group \"" + label + "\"");
    return recipe->weights;
  };
  std::map<std::string, Eigen::VectorXd> champions;  // expression -> the latest champion's rig weights
  std::vector<RankedPair> comparisons;
  for (const std::string& folder : options.annotations) {
    const AnnotationProject project = load_annotation_project(folder);
    // Each round's sample ids are among its own correspondences' candidates.
    const Correspondences round = load_correspondences(project.correspondences);
    const auto weights_of = [&](int64_t id) {
      const torch::Tensor w = round.candidate_weights(avatar, id).to(torch::kFloat64).contiguous();
      return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(w.data_ptr<double>(), w.numel()));
    };
    AnnotationStore store = AnnotationStore::open(project.database());
    for (const GroupProgress& g : store.progress().groups)
      if (g.champion) champions[g.label] = weights_of(*g.champion);
    if (options.comparisons)
      for (const Triplet& t : store.triplets(true))
        comparisons.push_back({recipe_of(t.anchor), weights_of(t.positive), weights_of(t.negative)});
  }
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
  const Eigen::MatrixXd metric = face_metric(load_dataset_rig(avatar), avatar);
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
