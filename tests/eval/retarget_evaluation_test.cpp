// Tests for eval/retarget_evaluation.h: the end-to-end check against the rig's ground truth.
#include "eval/retarget_evaluation.h"

#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "core/error.h"
#include "correspond/correspondence.h"
#include "data/test_faces.h"
#include "geometry/controller_correspondence.h"
#include "geometry/mesh_io.h"
#include "geometry/rig.h"
#include "tiny_correspondence.h"

using namespace retarget;
namespace fs = std::filesystem;

namespace {

struct Fixture {
  std::string correspondences, faces;
};

const Fixture& evaluation_fixture() {
  static const Fixture f = [] {
    const test::TinyCorrespondenceData& data = test::tiny_correspondence_data();
    const fs::path dir = test::process_scratch_dir("retarget_evaluation");
    Fixture out{(dir / "correspondences").string(), (dir / "faces").string()};
    CorrespondenceOptions o;
    o.group_size = 4;
    o.progress = nullptr;
    build_correspondences(data.human, data.avatar, data.run, out.correspondences, o);
    write_test_faces(data.human, out.faces);
    return out;
  }();
  return f;
}

// Writes, for every face, the avatar mesh `make(face)` into `folder`.
template <typename Make>
void write_method(const std::string& folder, const TestFaces& faces, const Rig& rig, Make make) {
  for (const TestFace& face : faces.faces)
    write_mesh((fs::path(folder) / fs::path(face.file).filename()).string(), with_positions(rig.neutral, make(face)));
}

}  // namespace

TEST_CASE("evaluate_retargeting scores the ground truth as perfect and the neutral face as wrong") {
  const test::TinyCorrespondenceData& data = test::tiny_correspondence_data();
  const Fixture& f = evaluation_fixture();
  const TestFaces faces = load_test_faces(f.faces);
  const Rig rig = load_rig((fs::path(data.avatar).parent_path() / "rig").string());
  const ControllerCorrespondence table = load_controller_correspondence(data.table);
  const fs::path dir = test::scratch_dir("retarget_evaluation_methods");
  fs::create_directories(dir / "truth");
  fs::create_directories(dir / "still");
  write_method((dir / "truth").string(), faces, rig, [&](const TestFace& face) {
    const auto mapped = controller_weights_from_human(table, face.weights);
    Eigen::VectorXd w = Eigen::VectorXd::Zero(rig.controller_count());
    for (int c = 0; c < rig.controller_count(); ++c) w(c) = mapped.at(rig.controllers[c].name);
    return rig.evaluate(w);
  });
  write_method((dir / "still").string(), faces, rig, [&](const TestFace&) { return rig.neutral.vertices; });

  RetargetEvaluationOptions o;
  o.faces = f.faces;
  o.correspondences = f.correspondences;
  o.methods = {{"truth", (dir / "truth").string()}, {"still", (dir / "still").string()}};
  o.table = data.table;
  o.out = (dir / "eval").string();
  o.render_size = 64;
  const RetargetEvaluation r = evaluate_retargeting(o);
  REQUIRE(r.ground_truth);
  REQUIRE(r.methods.size() == 5);
  CHECK(r.methods[0].name == "neutral");
  CHECK(r.methods[1].name == "dt");
  CHECK(r.methods[2].name == "dt_rig");
  const MethodScore& neutral = r.methods[0];
  const MethodScore& truth = r.methods[3];
  const MethodScore& still = r.methods[4];
  CHECK(truth.name == "truth");
  CHECK(truth.mean_mm < 1e-3);
  CHECK(truth.moving_mm < 1e-3);
  CHECK(truth.weight_error < 1e-4);
  CHECK(truth.weight_error_active < 1e-4);
  CHECK(truth.weight_error_relative < 1e-4);
  CHECK(truth.fraction_of_neutral < 1e-3);
  CHECK(still.mean_mm > 1.0);
  // The still face is right only for the neutral expression.
  CHECK(still.expression_mean_mm.at("neutral") < 1e-3);
  CHECK(still.expression_mean_mm.at("A") > 1.0);
  CHECK(still.weight_error > 0.05);
  // ... and it is the neutral answer: the same figures, a fraction of 1, a relative weight error
  // of 1 (all-zero weights), and over the moving vertices a larger error than over all of them.
  CHECK(still.mean_mm == Approx(neutral.mean_mm));
  CHECK(still.fraction_of_neutral == Approx(1.0));
  CHECK(neutral.weight_error_relative == Approx(1.0));
  CHECK(neutral.weight_active_fraction_of_neutral == Approx(1.0));
  CHECK(neutral.moving_mm >= neutral.mean_mm);
  CHECK(r.moving_vertices > 0);
  // The neutral answer's active-controller error is the truth's mean active weight: nothing moves.
  CHECK(neutral.weight_error_active > neutral.weight_error);
  CHECK(fs::file_size(r.sheet_path) > 1000);
  CHECK(fs::exists(fs::path(o.out) / "dt" / faces.faces[0].file));
  // The sheet shows the worst expressions of the last method (the still face: the ones that move most).
  REQUIRE_FALSE(r.sheet_expressions.empty());
  CHECK(r.sheet_expressions.front().find("neutral") == std::string::npos);
  CHECK(r.sheet_expressions.back().find("neutral") != std::string::npos);

  std::ifstream in(r.metrics_path);
  const nlohmann::json metrics = nlohmann::json::parse(in);
  CHECK(metrics["methods"]["truth"]["mean_mm"].get<double>() == Approx(truth.mean_mm));
  CHECK(metrics["methods"]["neutral"]["fraction_of_neutral"].get<double>() == Approx(1.0));
  CHECK(metrics["methods"]["still"]["expression_moving_mm"]["A"].get<double>() > 1.0);
  CHECK(metrics["moving_vertices"].get<int>() == r.moving_vertices);
  CHECK(metrics["samples"].get<int>() == static_cast<int>(faces.faces.size()));
}

TEST_CASE("evaluate_retargeting names a missing output and refuses bad options") {
  const test::TinyCorrespondenceData& data = test::tiny_correspondence_data();
  const Fixture& f = evaluation_fixture();
  const fs::path dir = test::scratch_dir("retarget_evaluation_bad");
  RetargetEvaluationOptions o;
  o.faces = f.faces;
  o.correspondences = f.correspondences;
  o.table = data.table;
  o.out = (dir / "eval").string();
  o.deformation_transfer = false;
  o.neutral = false;
  o.methods = {{"empty", dir.string()}};
  CHECK_THROWS_WITH(evaluate_retargeting(o), Catch::Contains("has no output for"));
  o.methods = {{"a", dir.string()}, {"a", dir.string()}};
  CHECK_THROWS_WITH(evaluate_retargeting(o), Catch::Contains("used twice"));
  o.methods = {};
  CHECK_THROWS_WITH(evaluate_retargeting(o), Catch::Contains("nothing to evaluate"));
  o.neutral = true;
  o.sheet = "best";
  CHECK_THROWS_WITH(evaluate_retargeting(o), Catch::Contains("--sheet") && Catch::Contains("'worst' or 'first'"));
  o.sheet = "worst";
  o.sheet_method = "full";
  CHECK_THROWS_WITH(evaluate_retargeting(o), Catch::Contains("--sheet-method") && Catch::Contains("'full'"));
}

TEST_CASE("evaluate_retargeting scores the references and the unseen blends apart") {
  const test::TinyCorrespondenceData& data = test::tiny_correspondence_data();
  const Fixture& f = evaluation_fixture();
  const fs::path dir = test::scratch_dir("retarget_evaluation_blends");
  TestFacesOptions fo;
  fo.blends.count = 4;
  const TestFaces faces = write_test_faces(data.human, (dir / "faces").string(), fo);
  const Rig rig = load_rig((fs::path(data.avatar).parent_path() / "rig").string());
  const ControllerCorrespondence table = load_controller_correspondence(data.table);
  fs::create_directories(dir / "truth");
  write_method((dir / "truth").string(), faces, rig,
               [&](const TestFace& face) { return rig.evaluate(rig_weights_from_human(table, rig, face.weights)); });

  // A method whose face depends on who makes the expression: the truth moved 0.01 units along x
  // per person (the first person's unmoved).
  std::map<std::string, int> person_index;
  for (const TestFace& face : faces.faces) person_index.emplace(face.subject, static_cast<int>(person_index.size()));
  fs::create_directories(dir / "personal");
  write_method((dir / "personal").string(), faces, rig, [&](const TestFace& face) {
    Positions p = rig.evaluate(rig_weights_from_human(table, rig, face.weights));
    p.col(0).array() += 0.01 * person_index.at(face.subject);
    return p;
  });

  RetargetEvaluationOptions o;
  o.faces = (dir / "faces").string();
  o.correspondences = f.correspondences;
  o.methods = {{"personal", (dir / "personal").string()}, {"truth", (dir / "truth").string()}};
  o.table = data.table;
  o.out = (dir / "eval").string();
  o.render_size = 64;
  const RetargetEvaluation r = evaluate_retargeting(o);
  REQUIRE(r.ground_truth);
  REQUIRE(r.sets.size() == 2);
  std::ifstream metrics_in(r.metrics_path);
  const double r_mm = nlohmann::json::parse(metrics_in)["mm_per_unit"].get<double>();
  const std::vector<MethodScore>& references = r.sets.at(kReferenceSet);
  const std::vector<MethodScore>& blends = r.sets.at(kBlendSet);
  REQUIRE(references.size() == r.methods.size());
  REQUIRE(blends.size() == r.methods.size());
  CHECK(references.front().samples + blends.front().samples == r.methods.front().samples);
  CHECK(blends.front().samples == 4 * static_cast<int>(faces.faces.size() / (4 + 4)));  // 4 blends per person
  for (const auto* set : {&references, &blends}) {
    CHECK(set->front().name == "neutral");
    CHECK(set->front().moving_fraction_of_neutral == Approx(1.0));
    CHECK(set->back().name == "truth");
    CHECK(set->back().moving_mm < 1e-3);
    // The same expression from every person gives one face: the truth and the neutral answer
    // do not depend on who makes it; deformation transfer carries each person's own shape.
    CHECK(set->back().identity_spread_mm < 1e-6);
    CHECK(set->front().identity_spread_mm < 1e-6);
    // Two people, 0.01 units apart: each lies 0.005 units from their mean.
    REQUIRE(person_index.size() == 2);
    const MethodScore& personal = (*set)[set->size() - 2];
    REQUIRE(personal.name == "personal");
    CHECK(personal.identity_spread_mm == Approx(0.005 * r_mm).epsilon(1e-6));
  }
  // The blends move the face: the neutral answer is wrong on them, and each set's figures are its own.
  CHECK(blends.front().moving_mm > 0.5);
  CHECK(blends.front().expression_moving_mm.count("blend000") == 1);
  CHECK(references.front().expression_moving_mm.count("blend000") == 0);

  std::ifstream in(r.metrics_path);
  const nlohmann::json metrics = nlohmann::json::parse(in);
  CHECK(metrics["sets"]["blends"]["samples"].get<int>() == blends.front().samples);
  CHECK(metrics["sets"]["blends"]["methods"]["neutral"]["moving_mm"].get<double>() == Approx(blends.front().moving_mm));
  CHECK(metrics["sets"]["references"]["methods"]["truth"]["moving_fraction_of_neutral"].get<double>() < 1e-3);

  // comparison.csv: a row per method and set, "all" first, the same figures.
  std::ifstream csv(r.table_path);
  std::vector<std::string> rows;
  for (std::string line; std::getline(csv, line);) rows.push_back(line);
  REQUIRE(rows.size() == 1 + 3 * r.methods.size());  // "all" and the two sets
  CHECK(rows[0] ==
        "set,method,faces,mean_mm,moving_mm,moving_x_neutral,max_mm,weight_error_active,weights_x_neutral,"
        "identity_spread_mm");
  CHECK(rows[1].rfind("all,neutral," + std::to_string(r.methods.front().samples) + ",", 0) == 0);
  CHECK(rows[1].find(",1.0000,") != std::string::npos);  // the neutral is x1 of itself
  CHECK(rows.back().rfind("references,truth,", 0) == 0);
}
