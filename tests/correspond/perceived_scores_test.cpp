// Tests for correspond/perceived_scores.h: simulated annotators with their own reading of the
// avatar, judging faces in mm.
#include "correspond/perceived_scores.h"

#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <filesystem>

#include "annotate/annotation_store.h"
#include "core/error.h"
#include "correspond/annotation_project.h"
#include "correspond/correspondence.h"
#include "data/dataset.h"
#include "tiny_correspondence.h"

using namespace retarget;
namespace fs = std::filesystem;

namespace {

const std::vector<std::string> kShapes = {"mouthSmile_L", "mouthSmile_R", "mouthFrown_L", "mouthDimple_L",
                                          "eyeBlink_L",   "eyeBlink_R",   "jawOpen",      "browInnerUp"};

const Correspondences& tiny_correspondences() {
  static const Correspondences c = [] {
    const test::TinyCorrespondenceData& data = test::tiny_correspondence_data();
    const fs::path dir = test::process_scratch_dir("perceived_scores");
    CorrespondenceOptions o;
    o.group_size = 8;
    o.progress = nullptr;
    build_correspondences(data.human, data.avatar, data.run, (dir / "c").string(), o);
    return load_correspondences((dir / "c").string());
  }();
  return c;
}

}  // namespace

TEST_CASE("neighbouring shapes share the face region and the side", "[perceived]") {
  CHECK(neighbouring_shapes("mouthSmile_L", kShapes) == std::vector<std::string>{"mouthFrown_L", "mouthDimple_L"});
  CHECK(neighbouring_shapes("eyeBlink_R", kShapes).empty());  // the other eye is not a neighbour
  CHECK(neighbouring_shapes("jawOpen", kShapes).empty());
  CHECK(neighbouring_shapes("browInnerUp", {"browInnerUp", "browOuterUpLeft", "browDown"}) ==
        std::vector<std::string>{"browDown"});
}

TEST_CASE("an annotator's reading: the table itself without perturbation, its own with, seeded", "[perceived]") {
  const ControllerCorrespondence table = {{"smile", {{"mouthSmile_L", 1.0}, {"mouthSmile_R", 1.0}}},
                                          {"blinkL", {{"eyeBlink_L", 1.0}}},
                                          {"jaw", {{"jawOpen", 0.8}}},
                                          {"ears", {}}};
  ReadingOptions exact;
  exact.share_spread = exact.neighbour_rate = exact.reread_rate = exact.drop_rate = 0;
  CHECK(annotator_reading(table, kShapes, exact, 3) == table);

  ReadingOptions o;  // the defaults
  const ControllerCorrespondence a = annotator_reading(table, kShapes, o, 3);
  CHECK(a == annotator_reading(table, kShapes, o, 3));
  CHECK(a != table);
  REQUIRE(a.size() == table.size());
  CHECK(a.at("ears").empty());
  // Over many annotators: shares spread around the table's, rows of two shapes now and then read
  // as one, rows now and then not understood, shares now and then on a neighbour.
  int rereads = 0, drops = 0, neighbours = 0;
  double log_sum = 0;
  int jaws = 0;
  for (uint64_t seed = 0; seed < 400; ++seed) {
    const ControllerCorrespondence r = annotator_reading(table, kShapes, o, seed);
    rereads += r.at("smile").size() == 1;
    drops += r.at("blinkL").empty();
    neighbours += r.at("smile").count("mouthFrown_L") + r.at("smile").count("mouthDimple_L");
    if (r.at("jaw").count("jawOpen")) log_sum += std::log(r.at("jaw").at("jawOpen") / 0.8), ++jaws;
    for (const auto& [controller, row] : r)
      for (const auto& [shape, share] : row) CHECK(share > 0);
  }
  CHECK(rereads > 400 * 0.2);
  CHECK(rereads < 400 * 0.4);
  CHECK(drops > 5);
  CHECK(drops < 40);
  CHECK(neighbours > 20);
  REQUIRE(jaws > 300);
  CHECK(std::abs(log_sum / jaws) < 0.06);  // no bias in the shares' scale

  o.neighbour_rate = 2;
  CHECK_THROWS_WITH(annotator_reading(table, kShapes, o, 1), Catch::Contains("reading.neighbour_rate"));
}

TEST_CASE("perceived scores: mm over the regions, zero for the imagined face, ranked like the truth", "[perceived]") {
  const test::TinyCorrespondenceData& data = test::tiny_correspondence_data();
  const Correspondences& c = tiny_correspondences();
  const Dataset human = load_dataset(c.human_dataset), avatar = load_dataset(c.avatar_dataset);
  const ControllerCorrespondence table = load_controller_correspondence(data.table);
  const std::vector<CandidateScores> scores = perceived_scores(c, human, avatar, {table, {}});
  REQUIRE(scores.size() == 2);
  const GroundTruth truth = ground_truth_scores(c, human, avatar, table, data.table);
  int agree = 0, pairs = 0;
  std::map<int64_t, double> moved;  // sample -> its score for the reading that understands nothing
  for (const auto& [label, candidates] : scores[0]) {
    REQUIRE(candidates.size() == static_cast<size_t>(c.group_size));
    const auto& weights = truth.scores.at(label);
    for (const auto& [a, sa] : candidates) {
      CHECK(std::isfinite(sa));
      CHECK(sa >= 0);
      for (const auto& [b, sb] : candidates)
        if (a < b && std::abs(weights.at(a) - weights.at(b)) > 0.1)
          agree += (sa < sb) == (weights.at(a) < weights.at(b)), ++pairs;
    }
    // A reading that understands nothing imagines the neutral face: the score is how far the
    // candidate moves, the same for every group.
    for (const auto& [sample, s] : scores[1].at(label)) {
      const auto [it, fresh] = moved.emplace(sample, s);
      if (!fresh) CHECK(s == Approx(it->second));
    }
  }
  REQUIRE(pairs > 20);
  CHECK(agree > 0.8 * pairs);  // faces judged in mm mostly agree with the table's weights
}
