#include "correspond/belief_rounds.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/error.h"
#include "correspond/annotation_evidence.h"
#include "correspond/annotation_project.h"
#include "correspond/rig_face_metric.h"
#include "geometry/controller_correspondence.h"

namespace retarget {

namespace {

ControllerMap prior_map(const std::string& path, const Dataset& avatar, const std::vector<std::string>& shapes) {
  if (is_controller_map_file(path)) {
    ControllerMap map = load_controller_map(path);
    if (map.controllers != avatar.controllers)
      throw Error(path, fmt::format("maps {} controllers, not the {} of the avatar dataset {}", map.controllers.size(),
                                    avatar.controllers.size(), avatar.folder));
    if (map.shapes != shapes)
      throw Error(path, fmt::format("maps {} shapes, not the face model's {}", map.shapes.size(), shapes.size()));
    return map;
  }
  const ControllerCorrespondence table = load_controller_correspondence(path);
  check_controller_correspondence(table, avatar.controllers, shapes, path);
  ControllerMap map = controller_map_from_table(table, avatar.controllers, shapes);
  map.prior = std::filesystem::absolute(path).lexically_normal().string();
  return map;
}

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

BeliefRounds belief_from_rounds(const std::string& prior, const Dataset& human, const Dataset& avatar,
                                const std::vector<std::string>& projects, const BeliefSearchOptions& options) {
  if (human.recipes.empty())
    throw Error(human.folder, "has no expression recipes: the belief search learns a map from recipe weights");
  const std::vector<std::string> shapes = blendshape_names(human.source);
  if (shapes.empty()) throw Error(human.source, "cannot read the face model's blendshape names");
  const Rig rig = load_dataset_rig(avatar);
  const ControllerMap start = prior_map(prior, avatar, shapes);
  BeliefRounds rounds{MapBelief(start, rig_lower(rig), rig_upper(rig), options),
                      rig_face_metric(rig, avatar, human_rows(start)), 0};
  // Each comparison with its own round's recipe: rounds over blends and over the references pool.
  for (const JudgedComparison& t : load_annotation_evidence(projects, avatar, /*derived=*/false).comparisons) {
    if (t.tie_break) continue;
    rounds.belief.observe(rounds.belief.recipe_vector(t.recipe), rounds.metric, t.positive, t.negative);
    ++rounds.comparisons;
  }
  return rounds;
}

}  // namespace retarget
