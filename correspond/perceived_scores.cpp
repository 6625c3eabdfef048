#include "correspond/perceived_scores.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>

#include "core/config.h"
#include "core/error.h"
#include "core/random.h"
#include "correspond/annotation_project.h"
#include "correspond/correspondence.h"
#include "data/dataset.h"
#include "geometry/face_model.h"
#include "geometry/metrics.h"
#include "geometry/rig_footprint.h"

namespace retarget {

void ReadingOptions::validate(const std::string& key_path) const {
  require(std::isfinite(share_spread) && share_spread >= 0, key_path + ".share_spread",
          fmt::format("expected a number >= 0, got {}", share_spread));
  for (const auto& [name, value] : {std::pair<const char*, double>{"neighbour_rate", neighbour_rate},
                                    {"reread_rate", reread_rate},
                                    {"drop_rate", drop_rate}})
    require(std::isfinite(value) && value >= 0 && value <= 1, key_path + "." + name,
            fmt::format("expected a probability in [0, 1], got {}", value));
}

namespace {

// The name's leading lower-case word ("mouth" of "mouthSmile_L") and its side ("L", "R" or "").
std::pair<std::string, std::string> word_and_side(const std::string& name) {
  size_t end = 0;
  while (end < name.size() && std::islower(static_cast<unsigned char>(name[end]))) ++end;
  std::string side;
  const auto ends_with = [&](const std::string& tail) {
    return name.size() > tail.size() && name.compare(name.size() - tail.size(), tail.size(), tail) == 0;
  };
  if (ends_with("_L") || ends_with("Left")) side = "L";
  if (ends_with("_R") || ends_with("Right")) side = "R";
  return {name.substr(0, end), side};
}

}  // namespace

std::vector<std::string> neighbouring_shapes(const std::string& shape, const std::vector<std::string>& shapes) {
  const auto key = word_and_side(shape);
  std::vector<std::string> out;
  if (key.first.empty()) return out;
  for (const std::string& other : shapes)
    if (other != shape && word_and_side(other) == key) out.push_back(other);
  return out;
}

ControllerCorrespondence annotator_reading(const ControllerCorrespondence& table,
                                           const std::vector<std::string>& shapes, const ReadingOptions& options,
                                           uint64_t seed) {
  options.validate();
  Random random(seed);
  ControllerCorrespondence reading;
  for (const auto& [controller, row] : table) {
    std::map<std::string, double>& mine = reading[controller];
    // Every draw is made whatever the outcome, so one row's reading never moves another's.
    const bool drop = random.unit() <= options.drop_rate;
    const bool reread = random.unit() <= options.reread_rate;
    const uint64_t kept = random.below(std::max<uint64_t>(1, row.size()));
    uint64_t index = 0;
    for (const auto& [shape, share] : row) {
      const double factor = std::exp(options.share_spread * random.normal());
      const bool move = random.unit() <= options.neighbour_rate;
      const uint64_t pick = random.next();
      if (reread && row.size() > 1 && index++ != kept) continue;
      std::string read_as = shape;
      if (move) {
        const std::vector<std::string> near = neighbouring_shapes(shape, shapes);
        if (!near.empty()) read_as = near[pick % near.size()];
      }
      mine[read_as] += share * factor;
    }
    if (drop) mine.clear();
  }
  return reading;
}

std::vector<CandidateScores> perceived_scores(const Correspondences& c, const Dataset& human, const Dataset& avatar,
                                              const std::vector<ControllerCorrespondence>& readings) {
  const std::vector<ExpressionRecipe> recipes = simulation_recipes(human, avatar);
  if (avatar.eyes.left.empty() || avatar.eyes.right.empty())
    throw Error(avatar.folder, "the avatar dataset has no eyes, so a simulated annotator cannot judge in mm");
  const Rig rig = load_dataset_rig(avatar);
  const double mm = millimetres_per_unit(rig.neutral.vertices, avatar.eyes);

  // Per reading: the vertices of each region it sees (its own rows name the regions).
  std::vector<std::vector<std::vector<int>>> regions(readings.size());
  for (size_t r = 0; r < readings.size(); ++r) {
    std::map<std::string, std::vector<std::string>> row_names;
    for (const auto& [controller, row] : readings[r])
      for (const auto& [shape, share] : row) row_names[controller].push_back(shape);
    const RigFootprint footprint = rig_footprint(rig, 0.1 / mm, row_names);
    for (const auto& [name, vertices] : footprint.regions) regions[r].push_back(vertices);
    if (regions[r].empty()) regions[r].push_back(footprint.moving);
  }
  const auto distance = [&](const Positions& a, const Positions& b, size_t r) {
    double sum = 0;
    for (const std::vector<int>& region : regions[r]) {
      double d = 0;
      for (int v : region) d += (a.row(v) - b.row(v)).norm();
      sum += region.empty() ? 0 : d / static_cast<double>(region.size());
    }
    return mm * sum / static_cast<double>(regions[r].size());
  };

  std::vector<CandidateScores> scores(readings.size());
  std::vector<Positions> candidates(static_cast<size_t>(c.group_size));
  for (int64_t k = 0; k < c.expression_count(); ++k) {
    const std::string& label = c.expressions[k];
    const auto recipe =
        std::find_if(recipes.begin(), recipes.end(), [&](const ExpressionRecipe& e) { return e.name == label; });
    if (recipe == recipes.end())
      throw Error(human.recipes,
                  "no recipe for the expression \"" + label + "\" of the correspondences in " + c.folder);
    std::vector<int64_t> samples;
    for (int64_t p = 0; p < c.group_size; ++p) {
      const int64_t sample = c.groups[k][p].item<int64_t>();
      if (sample < 0 || sample >= c.candidate_count())
        throw Error(avatar.folder, fmt::format("has no sample {} (group \"{}\")", sample, label));
      const torch::Tensor w = c.candidate_weights(avatar, sample).to(torch::kFloat64).contiguous();
      candidates[static_cast<size_t>(p)] =
          rig.evaluate(Eigen::Map<const Eigen::VectorXd>(w.data_ptr<double>(), w.numel()));
      samples.push_back(sample);
    }
    for (size_t r = 0; r < readings.size(); ++r) {
      const Positions imagined = rig.evaluate(rig_weights_from_human(readings[r], rig, recipe->weights));
      for (size_t p = 0; p < samples.size(); ++p) scores[r][label][samples[p]] = distance(candidates[p], imagined, r);
    }
  }
  return scores;
}

}  // namespace retarget
