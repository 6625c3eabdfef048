#include "correspond/controller_meaning.h"

#include <catch2/catch.hpp>
#include <iostream>
#include <iterator>
#include <sstream>

#include "cli/commands.h"
#include "core/error.h"
#include "run_command.h"
#include "scratch.h"
#include "synthetic/synthetic_faces.h"
#include "test_support.h"

using Catch::Contains;
using namespace retarget;

namespace meaning_test {

// The synthetic default and the proposal for each of its avatars with `options`.
struct Proposed {
  SyntheticSet set;
  std::vector<ControllerMeaning> meanings;  // one per avatar, in set.avatars' order
};

Proposed propose_all(const ControllerMeaningOptions& options) {
  Proposed out;
  out.set = synthetic_set();
  for (const SyntheticAvatar& a : out.set.avatars)
    out.meanings.push_back(propose_controller_meaning(a.rig, out.set.human, options));
  return out;
}

// The share of the controllers with a human counterpart in the ground truth whose proposed main
// shape is in their true row.
struct Agreement {
  int agree = 0, rows = 0;
  double share() const { return static_cast<double>(agree) / rows; }
};

Agreement agreement(const SyntheticAvatar& avatar, const ControllerMeaning& meaning, bool print) {
  int agree = 0, rows = 0;
  for (const ControllerMeaningRow& row : meaning.rows) {
    const auto& truth = avatar.correspondence.at(row.controller);
    if (truth.empty()) continue;
    ++rows;
    const bool ok = truth.count(row.main_shape) > 0;
    agree += ok;
    if (print && !ok) std::cout << "    " << row.controller << ": " << row.main_shape << " (" << row.method << ")\n";
  }
  return {agree, rows};
}

// Mean over the human shapes the true table uses of the summed absolute difference between the rig
// weights the true table and `table` give for that shape at weight 1.
double weight_error(const SyntheticAvatar& avatar, const ControllerCorrespondence& table, const FaceModel& human) {
  double sum = 0;
  int n = 0;
  for (const Blendshape& b : human.expressions) {
    const Eigen::VectorXd t = rig_weights_from_human(avatar.correspondence, avatar.rig, {{b.name, 1.0}});
    if (t.cwiseAbs().sum() == 0) continue;
    sum += (t - rig_weights_from_human(table, avatar.rig, {{b.name, 1.0}})).cwiseAbs().sum();
    ++n;
  }
  return sum / n;
}

// The proposal's table with another Weights choice, from the evidence of its geometry rows.
ControllerCorrespondence reweighted(const ControllerMeaning& m, ControllerMeaningOptions::Weights weights) {
  ControllerCorrespondence table = m.table;
  for (const ControllerMeaningRow& row : m.rows) {
    if (row.method != "geometry") continue;
    double norm = 0;
    for (const MeaningCandidate& c : row.candidates)
      if (c.kept) norm += c.fitted * c.fitted;
    auto& out = table[row.controller];
    out.clear();
    for (const MeaningCandidate& c : row.candidates) {
      if (!c.kept) continue;
      const double w =
          weights == ControllerMeaningOptions::Weights::human ? c.human_weight : (norm > 0 ? c.fitted / norm : 0.0);
      if (w != 0) out[c.shape] = w;
    }
  }
  return table;
}

// A rig on the synthetic human's own mesh whose controllers are some of its expressions under
// ARKit-style names (other spellings), without landmarks.
Rig arkit_rig(const FaceModel& human, const std::vector<std::pair<std::string, std::string>>& names) {
  Rig rig;
  rig.name = "arkit";
  rig.source = "arkit/rig.yaml";
  rig.neutral = human.neutral;
  for (const auto& [controller, shape] : names) {
    Controller c;
    c.name = controller;
    c.offset = human.expressions[human.expression_index(shape)].offset;
    rig.controllers.push_back(c);
  }
  return rig;
}

// `retarget avatar meaning ARGS...` as the dispatcher calls it (argv[0] = "meaning"), its output
// captured.
int run_meaning(std::vector<std::string> args, std::string& printed) {
  return test::run_command(cli::avatar_meaning, "meaning", std::move(args), &printed);
}

}  // namespace meaning_test

TEST_CASE("controller meaning: names compare without case, separators or the side's spelling", "[meaning]") {
  CHECK(meaning_name_key("eyeBlinkLeft") == meaning_name_key("eyeBlink_L"));
  CHECK(meaning_name_key("eye_blink_l") == "eyeblinkl");
  CHECK(meaning_name_key("JawOpen") == meaning_name_key("jawOpen"));
  CHECK(meaning_name_key("mouthSmileRight") == meaning_name_key("mouthSmile_R"));
  CHECK(meaning_name_key("mouthLeft") == "mouthl");  // as the face model's mouthLeft reads: the same key
  CHECK(meaning_name_key("smileLeft") != meaning_name_key("mouthSmile_L"));
  CHECK(name_side("eyeBrowLeftDown") == "left");
  CHECK(name_side("mouthSmile_R") == "right");
  CHECK(name_side("eyeRightClose") == "right");
  CHECK(name_side("jawOpen") == "");
  CHECK(name_side("browsDown") == "");
}

TEST_CASE("controller meaning: an ARKit-named rig is mapped by name, without landmarks", "[meaning]") {
  const FaceModel human = synthetic_human();
  const Rig rig = meaning_test::arkit_rig(
      human, {{"eyeBlinkLeft", "eyeBlink_L"}, {"JawOpen", "jawOpen"}, {"mouth_smile_r", "mouthSmile_R"}});
  REQUIRE(rig.landmarks.empty());
  const ControllerMeaning m = propose_controller_meaning(rig, human);
  CHECK_FALSE(m.transferred);
  CHECK(m.table == ControllerCorrespondence{{"eyeBlinkLeft", {{"eyeBlink_L", 1.0}}},
                                            {"JawOpen", {{"jawOpen", 1.0}}},
                                            {"mouth_smile_r", {{"mouthSmile_R", 1.0}}}});
  for (const ControllerMeaningRow& row : m.rows) {
    CHECK(row.method == "name");
    CHECK(row.confidence == 1.0);
  }
}

TEST_CASE("controller meaning: bad input is refused with a message that names it", "[meaning]") {
  const FaceModel human = synthetic_human();
  SECTION("placeholders that move nothing are {} with a note, named like a human shape or not") {
    Rig rig = meaning_test::arkit_rig(human, {{"eyeBlinkLeft", "eyeBlink_L"}});
    rig.controllers.push_back({"earWiggle", Positions::Zero(rig.neutral.vertex_count(), 3), 0, 1});
    rig.controllers.push_back({"jawOpen", Positions::Zero(rig.neutral.vertex_count(), 3), 0, 1});
    const ControllerMeaning m = propose_controller_meaning(rig, human);
    CHECK(m.table ==
          ControllerCorrespondence{{"eyeBlinkLeft", {{"eyeBlink_L", 1.0}}}, {"earWiggle", {}}, {"jawOpen", {}}});
    for (const char* still : {"earWiggle", "jawOpen"}) {
      CAPTURE(still);
      CHECK(m.row(still).method == "none");
      CHECK_THAT(m.row(still).note, Contains("moves no vertex") && Contains("placeholder"));
    }
    CHECK(m.row("eyeBlinkLeft").method == "name");
  }
  SECTION("a rig whose controllers all move nothing: an error, not an all-empty table") {
    Rig rig = meaning_test::arkit_rig(human, {});
    rig.controllers.push_back({"earWiggle", Positions::Zero(rig.neutral.vertex_count(), 3), 0, 1});
    rig.controllers.push_back({"jawOpen", Positions::Zero(rig.neutral.vertex_count(), 3), 0, 1});
    CHECK_THAT(test::error_of([&] { propose_controller_meaning(rig, human); }),
               Contains("none of the rig's 2 controllers moves a vertex") && Contains("is this the right mesh"));
  }
  SECTION("no landmarks in common, when a controller needs geometry") {
    Rig rig = meaning_test::arkit_rig(human, {{"wiggle", "eyeBlink_L"}});
    rig.landmarks = {{"snout_tip", 3}, {"ear_left", 10}};
    const std::string message = test::error_of([&] { propose_controller_meaning(rig, human); });
    CHECK_THAT(message, Contains("share 0 landmark names") && Contains("snout_tip") && Contains("\"wiggle\"") &&
                            Contains("nose_tip"));
  }
  SECTION("a rig without controllers, a face model without expressions") {
    Rig rig = meaning_test::arkit_rig(human, {});
    CHECK_THAT(test::error_of([&] { propose_controller_meaning(rig, human); }), Contains("no controllers"));
    rig = meaning_test::arkit_rig(human, {{"eyeBlinkLeft", "eyeBlink_L"}});
    FaceModel empty = human;
    empty.expressions.clear();
    CHECK_THAT(test::error_of([&] { propose_controller_meaning(rig, empty); }), Contains("no expressions"));
  }
  SECTION("options") {
    ControllerMeaningOptions options;
    options.min_share = 0;
    CHECK_THAT(test::error_of([&] { options.validate(); }), Contains("controller_meaning.min_share"));
    options = {};
    options.min_confidence = 1;
    CHECK_THAT(test::error_of([&] { options.validate(); }), Contains("controller_meaning.min_confidence"));
    options = {};
    options.max_shapes = 0;
    CHECK_THAT(test::error_of([&] { options.validate(); }), Contains("controller_meaning.max_shapes"));
    options = {};
    options.landmark_weight = -1;
    CHECK_THAT(test::error_of([&] { options.validate(); }), Contains("controller_meaning.landmark_weight"));
    MeaningPictureOptions picture;
    picture.size = 10;
    CHECK_THAT(test::error_of([&] { picture.validate(); }), Contains("meaning_picture.size"));
  }
}

TEST_CASE("controller meaning: the synthetic avatars' tables, proposed", "[meaning]") {
  const meaning_test::Proposed p = meaning_test::propose_all({});
  meaning_test::Agreement pooled;
  for (size_t a = 0; a < p.set.avatars.size(); ++a) {
    const SyntheticAvatar& avatar = p.set.avatars[a];
    const ControllerMeaning& m = p.meanings[a];
    CAPTURE(avatar.rig.name);
    REQUIRE(m.rows.size() == avatar.rig.controllers.size());
    check_controller_correspondence(
        m.table,
        [&] {
          std::vector<std::string> names;
          for (const Controller& c : avatar.rig.controllers) names.push_back(c.name);
          return names;
        }(),
        synthetic_expression_names(), avatar.rig.name);
    const meaning_test::Agreement agree = meaning_test::agreement(avatar, m, true);
    std::cout << avatar.rig.name << ": main human shape in the true row for " << agree.agree << " of " << agree.rows
              << " controllers with a counterpart (names and geometry, " << m.seconds << " s)\n";
    CHECK(agree.share() >= 0.6);
    pooled.agree += agree.agree;
    pooled.rows += agree.rows;
    // Controllers without a human counterpart (ears, antennae, head squash, ...): {}.
    for (const ControllerMeaningRow& row : m.rows) {
      CAPTURE(row.controller, row.confidence);
      if (avatar.correspondence.at(row.controller).empty()) CHECK(m.table.at(row.controller).empty());
      // Confidence is a share; name rows are certain.
      CHECK(row.confidence >= 0);
      CHECK(row.confidence <= 1);
      if (row.method == "name") CHECK(row.confidence == 1);
      if (row.method == "none") CHECK(m.table.at(row.controller).empty());
    }
    // Mirror images found from the geometry have mirrored rows.
    for (const ControllerMeaningRow& row : m.rows) {
      if (row.mirror.empty() || row.mirror == row.controller) continue;
      const ControllerMeaningRow& other = m.row(row.mirror);
      CAPTURE(row.controller, row.mirror, row.main_shape, other.main_shape);
      CHECK(other.mirror == row.controller);
      CHECK(name_side(row.controller) != name_side(other.controller));
    }
  }
  std::cout << "all three: " << pooled.agree << " of " << pooled.rows << "\n";
  CHECK(pooled.share() >= 0.82);  // 44 of 51 measured; 41 without the landmark features
  // The default weights (main shape at 1) give rig weights nearer the truth than the fitted
  // human weights or the forward fit's.
  for (size_t a = 0; a < p.set.avatars.size(); ++a) {
    using W = ControllerMeaningOptions::Weights;
    const SyntheticAvatar& avatar = p.set.avatars[a];
    const double unit = meaning_test::weight_error(avatar, p.meanings[a].table, p.set.human);
    const double human =
        meaning_test::weight_error(avatar, meaning_test::reweighted(p.meanings[a], W::human), p.set.human);
    const double fitted =
        meaning_test::weight_error(avatar, meaning_test::reweighted(p.meanings[a], W::fitted), p.set.human);
    std::cout << avatar.rig.name << ": rig-weight error per human shape: unit " << unit << ", human " << human
              << ", fitted " << fitted << "\n";
    CHECK(unit <= human);
    CHECK(unit <= fitted);
  }
  // Every row's weights: the main shape at 1 (Weights::unit), the others positive.
  for (const ControllerMeaning& m : p.meanings)
    for (const ControllerMeaningRow& row : m.rows) {
      if (row.main_shape.empty()) continue;
      CHECK(m.table.at(row.controller).at(row.main_shape) == 1.0);
      for (const auto& entry : m.table.at(row.controller)) CHECK(entry.second > 0);
    }

  SECTION("the file reads back, with a confidence per row; a picture per controller") {
    const SyntheticAvatar& avatar = p.set.avatars[1];
    const ControllerMeaning& m = p.meanings[1];
    const auto dir = test::scratch_dir("controller_meaning");
    const std::string path = (dir / "correspondence.yaml").string();
    write_controller_meaning(path, avatar.rig, p.set.human, m);
    CHECK(load_controller_correspondence(path) == m.table);
    std::ifstream in(path);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    CHECK_THAT(text, Contains("  blinkLeft: {eyeBlink_L: 1}  # confidence ") && Contains("earWiggleLeft: {}  # "));
    MeaningPictureOptions options;
    options.size = 96;
    const Image picture = controller_meaning_picture(avatar.rig, p.set.human, m, "smileLeft", options);
    CHECK(picture.width == 4 * 96);
    CHECK(picture.height > 96);
    // The avatar's neutral and smile differ; so do the human's.
    const Image neutral_only = controller_meaning_picture(avatar.rig, p.set.human, m, "earsBack", options);
    CHECK(picture.rgb != neutral_only.rgb);
    CHECK_THAT(test::error_of([&] { controller_meaning_picture(avatar.rig, p.set.human, m, "nose", options); }),
               Contains("no controller \"nose\""));
  }
}

TEST_CASE("controller meaning: by geometry alone, on the synthetic avatars", "[meaning]") {
  ControllerMeaningOptions options;
  options.match_names = false;
  const meaning_test::Proposed p = meaning_test::propose_all(options);
  meaning_test::Agreement pooled;
  for (size_t a = 0; a < p.set.avatars.size(); ++a) {
    const meaning_test::Agreement agree = meaning_test::agreement(p.set.avatars[a], p.meanings[a], true);
    std::cout << p.set.avatars[a].rig.name << ": geometry alone: main human shape in the true row for " << agree.agree
              << " of " << agree.rows << "\n";
    CHECK(agree.share() >= 0.5);
    pooled.agree += agree.agree;
    pooled.rows += agree.rows;
    for (const ControllerMeaningRow& row : p.meanings[a].rows) CHECK(row.method != "name");
  }
  std::cout << "geometry alone, all three: " << pooled.agree << " of " << pooled.rows << "\n";
  CHECK(pooled.share() >= 0.78);  // 42 of 51 measured; 39 without the landmark features

  // What the landmark features add: the same without them gets fewer main shapes right.
  options.landmark_weight = 0;
  const meaning_test::Proposed vertices_only = meaning_test::propose_all(options);
  meaning_test::Agreement without;
  for (size_t a = 0; a < vertices_only.set.avatars.size(); ++a) {
    const meaning_test::Agreement agree =
        meaning_test::agreement(vertices_only.set.avatars[a], vertices_only.meanings[a], false);
    without.agree += agree.agree;
    without.rows += agree.rows;
  }
  std::cout << "geometry alone, without the landmark features: " << without.agree << " of " << without.rows << "\n";
  CHECK(without.agree < pooled.agree);
}

TEST_CASE("controller meaning: mirror images are the avatar's own, from its symmetry", "[meaning]") {
  // Every side's controller with a human counterpart pairs with the other side's of the same name
  // (a blink with the other blink, never with the other squint, however alike the human shapes
  // explain them); a controller without a side is its own mirror image. The synthetic rigs name
  // their sides truly. (Their ear wiggles and antenna bends, without a human counterpart, swing
  // both pieces the same way round, so they are no mirror images.)
  const SyntheticSet set = synthetic_set();
  for (const SyntheticAvatar& avatar : set.avatars) {
    ControllerMeaningOptions options;
    options.match_names = false;  // every row by geometry
    const ControllerMeaning m = propose_controller_meaning(avatar.rig, set.human, options);
    int sided = 0;
    for (const ControllerMeaningRow& row : m.rows) {
      CAPTURE(avatar.rig.name, row.controller, row.mirror);
      if (avatar.correspondence.at(row.controller).empty()) continue;
      if (name_side(row.controller).empty()) {
        if (!row.mirror.empty()) CHECK(row.mirror == row.controller);
        continue;
      }
      ++sided;
      std::string expected = row.controller;
      for (const auto& [a, b] : {std::pair<std::string, std::string>{"Left", "Right"}, {"Right", "Left"}})
        if (row.controller.size() > a.size() &&
            row.controller.compare(row.controller.size() - a.size(), a.size(), a) == 0) {
          expected = row.controller.substr(0, row.controller.size() - a.size()) + b;
          break;
        }
      CHECK(row.mirror == expected);
    }
    CHECK(sided >= 8);
  }
}

TEST_CASE("controller meaning: a human model whose right blink and squint are swapped pairs the same mirror images",
          "[meaning]") {
  // Mislabelled (or lopsided) human shapes change which shapes explain the right side's
  // controllers, not which controllers are each other's mirror image: those come from the
  // avatar. (Paired by the shares, blinkLeft, explained by eyeBlink_L, would pair with
  // squintRight, now explained by the shape named eyeBlink_R.)
  SyntheticSet set = synthetic_set();
  const Rig& fox = set.avatars[1].rig;
  REQUIRE(fox.name == "fox");
  FaceModel& human = set.human;
  std::swap(human.expressions[human.expression_index("eyeBlink_R")].offset,
            human.expressions[human.expression_index("eyeSquint_R")].offset);
  ControllerMeaningOptions options;
  options.match_names = false;
  const ControllerMeaning m = propose_controller_meaning(fox, human, options);
  CHECK(m.row("blinkLeft").mirror == "blinkRight");
  CHECK(m.row("blinkRight").mirror == "blinkLeft");
  CHECK(m.row("squintLeft").mirror == "squintRight");
  CHECK(m.row("squintRight").mirror == "squintLeft");
}

TEST_CASE("controller meaning: left and right come from the geometry, not from the names", "[meaning]") {
  const SyntheticSet set = synthetic_set();
  Rig fox = set.avatars[1].rig;
  REQUIRE(fox.name == "fox");
  // Named from the viewer's side, as the shared rabbit's brows are.
  for (Controller& c : fox.controllers) {
    if (c.name == "blinkLeft")
      c.name = "blinkRight";
    else if (c.name == "blinkRight")
      c.name = "blinkLeft";
  }
  const ControllerMeaning m = propose_controller_meaning(fox, set.human);
  CHECK(m.row("blinkLeft").main_shape == "eyeBlink_R");
  CHECK(m.row("blinkRight").main_shape == "eyeBlink_L");
  CHECK_THAT(m.row("blinkLeft").note, Contains("named left") && Contains("geometry kept"));
  CHECK(m.row("smileLeft").note.empty());
}

TEST_CASE("controller meaning: `retarget avatar meaning` writes the table and a picture per controller", "[meaning]") {
  const FaceModel human = synthetic_human();
  const auto dir = test::scratch_dir("avatar_meaning_command");
  write_face_model((dir / "human").string(), human);
  write_rig_folder((dir / "arkit").string(),
                   meaning_test::arkit_rig(human, {{"eyeBlinkLeft", "eyeBlink_L"}, {"JawOpen", "jawOpen"}}));
  const std::string face = (dir / "human" / "face_model.yaml").string();
  const std::string out = (dir / "out" / "correspondence.yaml").string();
  std::string printed;
  REQUIRE(meaning_test::run_meaning({"--rig", (dir / "arkit").string(), "--face-model", face, "--out", out,
                                     "--pictures", (dir / "pictures").string(), "--picture-size", "64"},
                                    printed) == 0);
  CHECK_THAT(printed, Contains("eyeBlinkLeft") && Contains("confidence 1.00 (name)") && Contains("pictures: 2"));
  CHECK(load_controller_correspondence(out) ==
        ControllerCorrespondence{{"eyeBlinkLeft", {{"eyeBlink_L", 1.0}}}, {"JawOpen", {{"jawOpen", 1.0}}}});
  CHECK(std::filesystem::is_regular_file(dir / "pictures" / "eyeBlinkLeft.png"));
  CHECK(std::filesystem::is_regular_file(dir / "pictures" / "JawOpen.png"));

  CHECK_THAT(test::error_of([&] {
               meaning_test::run_meaning({"--rig", (dir / "arkit").string(), "--out", out}, printed);
             }),
             Contains("--face-model"));
  CHECK_THAT(test::error_of([&] {
               meaning_test::run_meaning(
                   {"--rig", (dir / "arkit").string(), "--face-model", face, "--out", out, "--min-confidence", "2"},
                   printed);
             }),
             Contains("controller_meaning.min_confidence"));
  CHECK_THAT(test::error_of([&] {
               meaning_test::run_meaning(
                   {"--rig", (dir / "arkit").string(), "--face-model", face, "--out", out, "--landmark-weight", "-1"},
                   printed);
             }),
             Contains("controller_meaning.landmark_weight"));
}
