// Tests for correspond/controller_map.h and correspond/rig_head.h: the rig head.
#include "geometry/controller_map.h"

#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "annotate/annotation_store.h"
#include "cli/cli.h"
#include "core/error.h"
#include "correspond/annotation_evidence.h"
#include "correspond/annotation_project.h"
#include "correspond/controller_map_fit.h"
#include "correspond/correspondence.h"
#include "correspond/rig_head.h"
#include "data/dataset.h"
#include "data/test_faces.h"
#include "eval/retarget_evaluation.h"
#include "separable_face_model.h"
#include "tiny_correspondence.h"

using namespace retarget;
namespace fs = std::filesystem;

namespace {

// `retarget ARGS...` in process; its exit status, and what it wrote to stderr in *err.
int run_retarget(std::vector<std::string> args, std::string* err = nullptr) {
  args.insert(args.begin(), "retarget");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  std::ostringstream captured;
  std::streambuf* old = std::cerr.rdbuf(captured.rdbuf());
  const int status = cli::run(static_cast<int>(argv.size()), argv.data());
  std::cerr.rdbuf(old);
  if (err) *err = captured.str();
  return status;
}

}  // namespace

TEST_CASE("a controller map from a table reads it linearly; a fit learns a map from pairs", "[controller_map]") {
  const ControllerCorrespondence table = {{"smile", {{"s", 1.0}}}, {"jaw", {{"j", 0.5}}}, {"ears", {}}};
  const std::vector<std::string> controllers = {"ears", "jaw", "smile"}, shapes = {"j", "s", "x"};
  const ControllerMap prior = controller_map_from_table(table, controllers, shapes);
  const Eigen::VectorXd y = prior.apply({{"s", 0.6}, {"j", 0.3}, {"unknown", 1}});
  CHECK(y(0) == Approx(0));
  CHECK(y(1) == Approx(0.6));  // jaw at 0.5 means j at 1: j 0.3 is jaw 0.6
  CHECK(y(2) == Approx(0.6));
  // Clamped to ranges when given.
  CHECK(prior.apply({{"j", 1.0}}, Eigen::VectorXd::Zero(3), Eigen::VectorXd::Ones(3))(1) == Approx(1.0));

  // Pairs from a different truth: x moves the ears. Many pairs and a weak prior learn it; with
  // a strong prior the map stays near the table.
  std::vector<std::map<std::string, double>> human;
  Eigen::MatrixXd rig(30, 3);
  for (int k = 0; k < 30; ++k) {
    const double a = (k % 5) / 4.0, b = (k % 3) / 2.0, c = (k % 7) / 6.0;
    human.push_back({{"j", a}, {"s", b}, {"x", c}});
    rig.row(k) << 0.8 * c, 2 * a, b;
  }
  ControllerMapOptions o;
  o.prior_weight = 1e-4;
  const ControllerMap learnt = fit_controller_map(human, rig, controllers, shapes, &prior, o);
  CHECK(learnt.pairs == 30);
  const Eigen::VectorXd z = learnt.apply({{"x", 1.0}, {"j", 0.25}});
  CHECK(z(0) == Approx(0.8).margin(1e-2));
  CHECK(z(1) == Approx(0.5).margin(1e-2));
  o.prior_weight = 1e4;
  CHECK(fit_controller_map(human, rig, controllers, shapes, &prior, o).apply({{"x", 1.0}})(0) ==
        Approx(0).margin(1e-2));

  // The file round trip, and its errors.
  const fs::path dir = test::scratch_dir("controller_map");
  write_controller_map((dir / "map.yaml").string(), learnt);
  const ControllerMap back = load_controller_map((dir / "map.yaml").string());
  CHECK(back.controllers == controllers);
  CHECK((back.matrix - learnt.matrix).cwiseAbs().maxCoeff() < 1e-9);
  std::ofstream(dir / "bad.yaml") << "format: retarget-controller-map\ncontrollers: [a]\nshapes: [x, y]\n"
                                     "matrix:\n  - [1]\n";
  CHECK_THROWS_WITH(load_controller_map((dir / "bad.yaml").string()),
                    Catch::Contains("bad.yaml:5") && Catch::Contains("expected 2 numbers"));
  CHECK_THROWS_WITH(fit_controller_map(human, rig.topRows(3), controllers, shapes, nullptr),
                    Catch::Contains("30 human expressions"));
}

TEST_CASE("a controller map with a covariance reads a face as its most likely weights on the rig", "[controller_map]") {
  // Two controllers that move together (correlation 0.8), one shape. The map reads the shape as
  // c0 = -0.5 (past its range) and c1 = 0.5: clamped, (0, 0.5); the most likely point inside the
  // ranges moves c1 with c0: 0.5 + 0.8 * 0.5 = 0.9.
  ControllerMap map;
  map.controllers = {"c0", "c1"};
  map.shapes = {"s"};
  map.matrix.resize(2, 1);
  map.matrix << -0.5, 0.5;
  const Eigen::Vector2d lo(0, 0), hi(1, 1);
  CHECK(map.apply({{"s", 1.0}}, lo, hi).isApprox(Eigen::Vector2d(0, 0.5)));
  map.covariance.resize(2, 2);
  map.covariance << 1, 0.8, 0.8, 1;
  const Eigen::VectorXd read = map.apply({{"s", 1.0}}, lo, hi);
  CHECK(read(0) == Approx(0).margin(1e-9));
  CHECK(read(1) == Approx(0.9).epsilon(1e-6));
  // Scaled by the blend weight: r = 0.5 gives mean (-0.25, 0.25) and covariance 0.25 of it.
  CHECK(map.covariance_of(Eigen::VectorXd::Constant(1, 0.5)).isApprox(0.25 * map.covariance));
  CHECK(map.apply({{"s", 0.5}}, lo, hi)(1) == Approx(0.45).epsilon(1e-6));
  // The covariance travels beside the map file and comes back.
  const fs::path dir = test::scratch_dir("controller_map_covariance");
  const std::string path = (dir / "map.yaml").string();
  write_controller_map(path, map);
  CHECK(fs::exists(dir / "map.yaml.covariance.pt"));
  const ControllerMap back = load_controller_map(path);
  CHECK(back.covariance.isApprox(map.covariance));
  CHECK(back.apply({{"s", 1.0}}, lo, hi).isApprox(read));
  // A covariance of another size is named.
  map.covariance = Eigen::MatrixXd::Identity(3, 3);
  write_controller_map(path, map);
  CHECK_THROWS_WITH(load_controller_map(path), Catch::Contains("covariance") && Catch::Contains("expected [2, 2]"));
}

TEST_CASE("the ranked fit: comparisons move the map where they agree, the prior holds where they do not",
          "[controller_map]") {
  const std::vector<std::string> controllers = {"jaw", "smile"}, shapes = {"j", "s"};
  // The prior reads j as the smile and s as the jaw: wrong. The answers prefer the right reading.
  const ControllerMap prior =
      controller_map_from_table({{"jaw", {{"s", 1.0}}}, {"smile", {{"j", 1.0}}}}, controllers, shapes);
  std::vector<RankedPair> comparisons;
  for (int k = 1; k <= 10; ++k) {
    const double a = k / 10.0;
    Eigen::VectorXd right(2), wrong(2);
    right << a, 0;  // j at a: the jaw at a
    wrong << 0, a;
    comparisons.push_back({{{"j", a}}, right, wrong});
    comparisons.push_back({{{"s", a}}, Eigen::Vector2d(0, a), Eigen::Vector2d(a, 0)});
  }
  RankingOptions o;
  o.prior_weight = 0.01;
  const ControllerMap learnt = fit_controller_map_ranked(
      {}, Eigen::MatrixXd(0, 2), comparisons, Eigen::MatrixXd::Identity(2, 2), controllers, shapes, prior, o);
  const Eigen::VectorXd y = learnt.apply({{"j", 1.0}});
  CHECK(y(0) > y(1));  // the jaw now moves more than the smile for j
  // With a strong prior the answers barely move it.
  o.prior_weight = 1e4;
  const Eigen::VectorXd held = fit_controller_map_ranked({}, Eigen::MatrixXd(0, 2), comparisons,
                                                         Eigen::MatrixXd::Identity(2, 2), controllers, shapes, prior, o)
                                   .apply({{"j", 1.0}});
  CHECK(held(1) == Approx(1.0).margin(0.05));
  CHECK_THROWS_WITH(fit_controller_map_ranked({}, Eigen::MatrixXd(0, 2), comparisons, Eigen::MatrixXd::Identity(3, 3),
                                              controllers, shapes, prior, o),
                    Catch::Contains("3 x 3 metric"));
  o.steps = 0;
  CHECK_THROWS_WITH(fit_controller_map_ranked({}, Eigen::MatrixXd(0, 2), comparisons, Eigen::MatrixXd::Identity(2, 2),
                                              controllers, shapes, prior, o),
                    Catch::Contains("ranking.steps"));
}

TEST_CASE("the prior's weight is chosen by the comparisons of held-out expressions", "[controller_map]") {
  const std::vector<std::string> controllers = {"jaw", "smile"}, shapes = {"j", "s"};
  const ControllerMap wrong =
      controller_map_from_table({{"jaw", {{"s", 1.0}}}, {"smile", {{"j", 1.0}}}}, controllers, shapes);
  const ControllerMap right =
      controller_map_from_table({{"jaw", {{"j", 1.0}}}, {"smile", {{"s", 1.0}}}}, controllers, shapes);
  // Answers that read j as the jaw, on ten expressions of each shape.
  std::vector<RankedPair> comparisons;
  for (int k = 1; k <= 10; ++k) {
    const double a = k / 10.0;
    comparisons.push_back({{{"j", a}}, Eigen::Vector2d(a, 0), Eigen::Vector2d(0, a)});
    comparisons.push_back({{{"s", a}}, Eigen::Vector2d(0, a), Eigen::Vector2d(a, 0)});
  }
  const Eigen::MatrixXd metric = Eigen::MatrixXd::Identity(2, 2);
  RankingOptions o;
  o.steps = 200;
  // A prior the answers contradict is corrected: a finite weight wins.
  const PriorWeightChoice corrected =
      choose_prior_weight({}, Eigen::MatrixXd(0, 2), comparisons, metric, controllers, shapes, wrong, o);
  CHECK(std::isfinite(corrected.weight));
  REQUIRE(corrected.agreement.size() == 5);                 // the grid and the prior alone
  CHECK(corrected.agreement.back().second == Approx(0.0));  // the wrong prior agrees with no answer
  // A prior the answers confirm is kept as it is.
  const PriorWeightChoice kept =
      choose_prior_weight({}, Eigen::MatrixXd(0, 2), comparisons, metric, controllers, shapes, right, o);
  CHECK(std::isinf(kept.weight));
  CHECK(kept.agreement.back().second == Approx(1.0));
  CHECK_THROWS_WITH(
      choose_prior_weight({}, Eigen::MatrixXd(0, 2), comparisons, metric, controllers, shapes, right, o, {1.0}, 1),
      Catch::Contains("2 folds"));
}

TEST_CASE("the rig head learns from champions and carries unseen blends onto the rig", "[controller_map][rig_head]") {
  const test::TinyCorrespondenceData& data = test::tiny_correspondence_data();
  const fs::path dir = test::scratch_dir("rig_head");
  // People of a face model whose expressions can be told from identity (the tiny one's cannot),
  // onto the tiny avatar.
  FaceModel model = test::separable_face_model();
  model.landmarks = {{"corner00", 0}, {"corner10", 5}, {"corner01", 30}, {"corner11", 35}};
  write_face_model((dir / "face").string(), model);
  const std::string recipes = (dir / "recipes.yaml").string();
  std::ofstream(recipes) << "recipes:\n  - {name: neutral, weights: {}}\n  - {name: A, weights: {a: 1.0}}\n"
                            "  - {name: AB, weights: {a: 0.5, b: 1.0}}\n  - {name: C, weights: {c: 1.0}}\n";
  HumanDatasetOptions h;
  h.people = 8;
  h.test_people = 2;
  h.progress = nullptr;
  const std::string human_dataset = (dir / "human").string();
  build_human_dataset(load_face_model((dir / "face").string()), load_expression_recipes(recipes), recipes,
                      human_dataset, h);
  CorrespondenceOptions co;
  co.group_size = 4;
  co.progress = nullptr;
  build_correspondences(human_dataset, data.avatar, data.run, (dir / "c").string(), co);
  // Without an annotation or a prior there is nothing to learn from.
  RigHeadFitOptions o;
  o.correspondences = (dir / "c").string();
  CHECK_THROWS_WITH(fit_rig_head(o), Catch::Contains("--annotation"));

  // The zero-annotation path: the table alone is the map, and carries blends exactly.
  o.prior = data.table;
  const ControllerMap prior = fit_rig_head(o);
  CHECK(prior.pairs == 0);
  TestFacesOptions fo;
  fo.blends.count = 5;
  write_test_faces(human_dataset, (dir / "faces").string(), fo);
  const RigHeadApplyResult applied =
      apply_rig_head(prior, (dir / "faces").string(), (dir / "c").string(), (dir / "out").string());
  CHECK(applied.faces > 0);
  CHECK(fs::exists(applied.weights_csv));
  RetargetEvaluationOptions eo;
  eo.faces = (dir / "faces").string();
  eo.correspondences = (dir / "c").string();
  eo.methods = {{"head", (dir / "out").string()}};
  eo.table = data.table;
  eo.out = (dir / "eval").string();
  eo.render_size = 32;
  const RetargetEvaluation r = evaluate_retargeting(eo);
  // The table is the evaluation's: the map carries every face exactly, blends as well as references.
  CHECK(r.sets.at(kBlendSet).back().moving_mm < 1e-2 * r.sets.at(kBlendSet).front().moving_mm);
  CHECK(r.sets.at(kReferenceSet).back().moving_mm < 1e-2 * r.sets.at(kReferenceSet).front().moving_mm);

  // With an annotated project: one pair per champion.
  init_annotation_project((dir / "c").string(), (dir / "a").string());
  const Correspondences c = load_correspondences((dir / "c").string());
  const Dataset human = load_dataset(c.human_dataset), avatar = load_dataset(c.avatar_dataset);
  const GroundTruth truth =
      ground_truth_scores(c, human, avatar, load_controller_correspondence(data.table), data.table);
  AnnotationStore store = AnnotationStore::open(load_annotation_project((dir / "a").string()).database());
  run_simulated_annotation(store, truth.scores);
  o.annotations = {(dir / "a").string()};
  o.choose_prior_weight = false;
  const ControllerMap learnt = fit_rig_head(o);  // every comparison
  CHECK(learnt.pairs == static_cast<int>(c.expression_count()));
  CHECK(learnt.controllers == avatar.controllers);
  o.comparisons = false;  // the champions alone, closed form
  const ControllerMap champions = fit_rig_head(o);
  CHECK(champions.pairs == static_cast<int>(c.expression_count()));
  CHECK((champions.matrix - learnt.matrix).cwiseAbs().maxCoeff() > 0);
  // With the prior's weight chosen by the comparisons, the oracle's answers (the table itself)
  // confirm the prior: it is kept.
  o.comparisons = true;
  o.choose_prior_weight = true;
  const ControllerMap chosen = fit_rig_head(o);
  CHECK((chosen.matrix - prior.matrix).cwiseAbs().maxCoeff() < 1e-9);
}

TEST_CASE("retarget rig-map: fit and apply from the command line, bad options named", "[controller_map][cli]") {
  const test::TinyCorrespondenceData& d = test::tiny_correspondence_data();
  const fs::path dir = test::scratch_dir("rig_map_cli");
  const std::string corr = (dir / "c").string(), project = (dir / "p").string(), faces = (dir / "faces").string();
  REQUIRE(run_retarget({"correspond", "--human", d.human, "--avatar", d.avatar, "--avatar-vae", d.run, "--out", corr,
                        "--group-size", "4"}) == 0);
  REQUIRE(run_retarget({"annotate", "init", "--correspondences", corr, "--out", project}) == 0);
  REQUIRE(run_retarget({"annotate", "simulate", project, "--table", d.table}) == 0);
  REQUIRE(run_retarget({"faces", d.human, "--blends", "2", "--out", faces}) == 0);
  const std::string map = (dir / "map.yaml").string();
  CHECK(run_retarget({"rig-map", "fit", "--correspondences", corr, "--annotation", project, "--prior", d.table, "--out",
                      map}) == 0);
  CHECK(load_controller_map(map).pairs == 4);
  CHECK(run_retarget({"rig-map", "apply", map, "--faces", faces, "--correspondences", corr, "--out",
                      (dir / "o").string()}) == 0);
  CHECK(fs::exists(dir / "o" / "weights.csv"));
  CHECK(fs::exists(dir / "o" / (load_test_faces(faces).faces.back().file)));

  std::string err;
  CHECK(run_retarget(
            {"rig-map", "fit", "--correspondences", corr, "--prior", d.table, "--prior-weight", "fast", "--out", map},
            &err) == 1);
  CHECK_THAT(err, Catch::Contains("--prior-weight") && Catch::Contains("expected a number or auto"));
  CHECK(run_retarget({"rig-map", "apply", map, "--correspondences", corr, "--out", (dir / "o").string()}, &err) == 1);
  CHECK_THAT(err, Catch::Contains("expected --faces"));
  CHECK(run_retarget({"rig-map", "fit", "--correspondences", corr, "--out", map}, &err) == 1);
  CHECK_THAT(err, Catch::Contains("--annotation") && Catch::Contains("prior table"));
  CHECK(run_retarget({"rig-map", "bogus"}, &err) == 1);
  CHECK_THAT(err, Catch::Contains("unknown subcommand 'bogus'"));
}

TEST_CASE(
    "retarget correspond --informative and rig-map fit --belief: rounds of informative pairs from the command line",
    "[controller_map][cli][belief]") {
  const test::TinyCorrespondenceData& d = test::tiny_correspondence_data();
  const fs::path dir = test::scratch_dir("belief_cli");
  std::vector<std::string> evidence;
  for (int round = 1; round <= 3; ++round) {
    const std::string corr = (dir / ("c" + std::to_string(round))).string();
    const std::string project = (dir / ("p" + std::to_string(round))).string();
    std::vector<std::string> args{"correspond", "--human",       d.human, "--avatar",      d.avatar, "--avatar-vae",
                                  d.run,        "--start-table", d.table, "--informative", "--out",  corr};
    args.insert(args.end(), evidence.begin(), evidence.end());
    REQUIRE(run_retarget(args) == 0);
    const Correspondences c = load_correspondences(corr);
    CHECK(c.group_size == 2);  // the default with --informative
    CHECK(c.evidence.size() == static_cast<size_t>(round - 1));
    REQUIRE(run_retarget({"annotate", "init", "--correspondences", corr, "--out", project}) == 0);
    REQUIRE(run_retarget({"annotate", "simulate", project, "--table", d.table, "--seed", std::to_string(round)}) == 0);
    evidence.insert(evidence.end(), {"--evidence", project});
  }
  // The rig head's map of the three rounds, with `extra` options.
  const auto fit = [&](const std::string& name, std::vector<std::string> extra) {
    const std::string out = (dir / name).string();
    std::vector<std::string> args{"rig-map",
                                  "fit",
                                  "--correspondences",
                                  (dir / "c1").string(),
                                  "--annotation",
                                  (dir / "p1").string(),
                                  "--annotation",
                                  (dir / "p2").string(),
                                  "--annotation",
                                  (dir / "p3").string(),
                                  "--prior",
                                  d.table,
                                  "--belief",
                                  "--out",
                                  out};
    args.insert(args.end(), extra.begin(), extra.end());
    REQUIRE(run_retarget(args) == 0);
    const ControllerMap m = load_controller_map(out);
    CHECK(m.matrix.allFinite());
    CHECK(m.matrix.minCoeff() >= -1e-9);  // inside the ranges
    return m;
  };
  const std::string map = (dir / "map.yaml").string();
  const ControllerMap learnt = fit("map.yaml", {});  // refined by expectation propagation (the default)
  CHECK(learnt.pairs > 0);                           // the comparisons the belief observed
  CHECK(learnt.pairs <= 12);
  CHECK(fit("one_pass.yaml", {"--belief-passes", "0"}).pairs == learnt.pairs);
  // Each annotator read as one reading of a shared map: the answers name who gave them.
  CHECK(fit("shared.yaml", {"--belief-annotator-sd", "0.25"}).pairs == learnt.pairs);
  CHECK(fit("left_out.yaml", {"--belief-leave-one-out", "true"}).pairs == learnt.pairs);
  const AnnotationEvidence said = load_annotation_evidence(
      {(dir / "p1").string(), (dir / "p2").string(), (dir / "p3").string()}, load_dataset(d.avatar), false);
  REQUIRE(!said.comparisons.empty());
  for (const JudgedComparison& c : said.comparisons)
    CHECK((c.tie_break ? c.annotator.empty() : c.annotator.rfind("simulated-", 0) == 0));
  // A round over training blends (retarget dataset --blends) pools with the rounds over the references.
  const std::string blends = (dir / "blends").string();
  REQUIRE(run_retarget({"dataset", "--face-model", load_dataset(d.human).source, "--recipes", dataset_recipes(d.human),
                        "--blends", "3", "--people", "4", "--no-preview", "--out", blends}) == 0);
  const std::vector<ExpressionRecipe> with_blends = load_expression_recipes(dataset_recipes(blends));
  REQUIRE(with_blends.size() == 4 + 3);
  CHECK(with_blends.back().name == "train_blend002");
  CHECK(dataset_recipes(blends) == fs::absolute(fs::path(blends) / "recipes.yaml").lexically_normal().string());
  REQUIRE(run_retarget({"correspond", "--human", blends, "--avatar", d.avatar, "--avatar-vae", d.run, "--start-table",
                        d.table, "--informative", "--out", (dir / "cb").string()}) == 0);
  CHECK(load_correspondences((dir / "cb").string()).expression_count() == 7);
  REQUIRE(run_retarget(
              {"annotate", "init", "--correspondences", (dir / "cb").string(), "--out", (dir / "pb").string()}) == 0);
  REQUIRE(run_retarget({"annotate", "simulate", (dir / "pb").string(), "--table", d.table}) == 0);
  REQUIRE(run_retarget({"correspond", "--human", d.human, "--avatar", d.avatar, "--avatar-vae", d.run, "--start-table",
                        d.table, "--informative", "--evidence", (dir / "pb").string(), "--evidence",
                        (dir / "p1").string(), "--out", (dir / "c4").string()}) == 0);
  CHECK(load_correspondences((dir / "c4").string()).evidence_comparisons >= 7);
  // Bad settings are named.
  std::string err;
  CHECK(run_retarget({"rig-map", "fit", "--correspondences", (dir / "c1").string(), "--annotation",
                      (dir / "p1").string(), "--prior", d.table, "--belief", "--belief-lapse", "0.7", "--out", map},
                     &err) == 1);
  CHECK_THAT(err, Catch::Contains("--belief.lapse") && Catch::Contains("[0, 0.5)"));
  CHECK(run_retarget({"rig-map", "fit", "--correspondences", (dir / "c1").string(), "--annotation",
                      (dir / "p1").string(), "--belief", "--out", map},
                     &err) == 1);
  CHECK_THAT(err, Catch::Contains("--belief") && Catch::Contains("give --prior"));
  CHECK(
      run_retarget({"correspond", "--human", d.human, "--avatar", d.avatar, "--avatar-vae", d.run, "--start-table",
                    d.table, "--evidence", (dir / "p1").string(), "--group-size", "2", "--out", (dir / "bad").string()},
                   &err) == 1);
  CHECK_THAT(err, Catch::Contains("correspond.evidence") && Catch::Contains("informative"));
  // A round's search reads each answer once: refining is the rig head's alone.
  CHECK(run_retarget({"correspond", "--human", d.human, "--avatar", d.avatar, "--avatar-vae", d.run, "--start-table",
                      d.table, "--informative", "--belief-passes", "2", "--out", (dir / "bad").string()},
                     &err) == 1);
  CHECK_THAT(err, Catch::Contains("--belief-passes") && Catch::Contains("rig-map fit"));
  CHECK(run_retarget({"correspond", "--human", d.human, "--avatar", d.avatar, "--avatar-vae", d.run, "--start-table",
                      d.table, "--informative", "--belief-annotator-sd", "0.25", "--out", (dir / "bad").string()},
                     &err) == 1);
  CHECK_THAT(err, Catch::Contains("--belief-annotator-sd") && Catch::Contains("rig-map fit"));
  CHECK(run_retarget({"correspond", "--human", d.human, "--avatar", d.avatar, "--avatar-vae", d.run, "--start-table",
                      d.table, "--informative", "--belief-leave-one-out", "true", "--out", (dir / "bad").string()},
                     &err) == 1);
  CHECK_THAT(err, Catch::Contains("--belief-leave-one-out") && Catch::Contains("rig-map fit"));
  CHECK(run_retarget({"rig-map", "fit", "--correspondences", (dir / "c1").string(), "--annotation",
                      (dir / "p1").string(), "--prior", d.table, "--belief", "--belief-passes", "-1", "--out", map},
                     &err) == 1);
  CHECK_THAT(err, Catch::Contains("refine_passes"));
  CHECK(
      run_retarget({"rig-map", "fit", "--correspondences", (dir / "c1").string(), "--annotation", (dir / "p1").string(),
                    "--prior", d.table, "--belief", "--belief-jackknife-also", "2,x", "--out", map},
                   &err) == 1);
  CHECK_THAT(err, Catch::Contains("--belief-jackknife-also") && Catch::Contains("'x'"));
  CHECK(
      run_retarget({"rig-map", "fit", "--correspondences", (dir / "c1").string(), "--annotation", (dir / "p1").string(),
                    "--prior", d.table, "--belief", "--belief-jackknife-also", "2,-1", "--out", map},
                   &err) == 1);
  CHECK_THAT(err, Catch::Contains("jackknife_alternatives"));
  CHECK(run_retarget({"correspond", "--human", d.human, "--avatar", d.avatar, "--avatar-vae", d.run, "--start-table",
                      d.table, "--informative", "--belief-jackknife-also", "2", "--out", (dir / "bad").string()},
                     &err) == 1);
  CHECK_THAT(err, Catch::Contains("--belief-jackknife-also") && Catch::Contains("rig-map fit"));
}
