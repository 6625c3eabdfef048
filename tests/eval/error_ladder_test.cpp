#include "eval/error_ladder.h"

#include <fmt/format.h>
// LibTorch before Catch2: glog, which LibTorch includes, defines a CHECK macro of its own.
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>

#include "cli/cli.h"
#include "core/config.h"
#include "core/error.h"
#include "correspond/correspondence.h"
#include "data/dataset.h"
#include "data/test_faces.h"
#include "geometry/controller_correspondence.h"
#include "geometry/metrics.h"
#include "geometry/rig.h"
#include "geometry/rigid_alignment.h"
#include "tiny_correspondence.h"
#include "train/vae_config.h"
#include "train/vae_trainer.h"
#include "translate/translation_config.h"
#include "translate/translation_trainer.h"

using namespace retarget;
using namespace retarget::test;
namespace fs = std::filesystem;

namespace {

// The tiny data of tests/tiny_correspondence.h (human: 8 people, 2 of them held out, x
// neutral, A, AB, C; avatar: 60 samples of a 4-controller rig, 12 held out; its VAE and table)
// with a human VAE, correspondences and a translation run trained for three epochs on L_P only.
struct LadderFixture {
  std::string human_vae, correspondences, translation, table, human_dataset, avatar_dataset;
};

const LadderFixture& ladder_fixture() {
  static const LadderFixture f = [] {
    const TinyCorrespondenceData& data = tiny_correspondence_data();
    const fs::path dir = process_scratch_dir("error_ladder_fixture");
    LadderFixture l;
    l.human_dataset = data.human;
    l.avatar_dataset = data.avatar;
    l.table = data.table;
    l.human_vae = (dir / "human_vae").string();
    VaeTrainOptions quiet_vae;
    quiet_vae.progress = nullptr;
    const std::string human_config = fmt::format(
        "task: vae\n"
        "data: {{dataset: {}, validation_fraction: 0.2}}\n"
        "model: {{channels: [9, 8, 4, 1], hidden: 32, latent: 3, order: 2}}\n"
        "loss: {{kl_weight: 1.0e-4}}\n"
        "optimiser: {{lr: 1.0e-2}}\n"
        "training: {{epochs: 3, batch_size: 4, checkpoint_every: 1, seed: 11, threads: 1}}\n"
        "output: {}\n",
        data.human, l.human_vae);
    train_vae(read_vae_train_config(ConfigNode::parse(human_config, "human_vae.yaml")), quiet_vae);
    CorrespondenceOptions c;
    c.group_size = 6;
    c.progress = nullptr;
    l.correspondences = (dir / "corr").string();
    build_correspondences(data.human, data.avatar, data.run, l.correspondences, c);
    l.translation = (dir / "translation").string();
    TranslationTrainOptions quiet_translation;
    quiet_translation.progress = nullptr;
    const std::string translation_config = fmt::format(
        "task: translation\n"
        "data: {{human_vae: {}, avatar_vae: {}, correspondences: {}}}\n"
        "model: {{hidden: 16}}\n"
        "training: {{batch_size: 5, checkpoint_every: 1, seed: 3, threads: 1}}\n"
        "stages:\n"
        "  - {{name: paired, epochs: 3, lr: 1.0e-2, weights: {{paired: 1, group: 0, triplet: 0}}}}\n"
        "output: {}\n",
        l.human_vae, data.run, l.correspondences, l.translation);
    train_translation(read_translation_train_config(ConfigNode::parse(translation_config, "translation.yaml")),
                      quiet_translation);
    return l;
  }();
  return f;
}

ErrorLadderOptions options_for(const std::string& out) {
  const LadderFixture& f = ladder_fixture();
  ErrorLadderOptions o;
  o.correspondences = f.correspondences;
  o.translation = f.translation;
  o.table = f.table;  // the tiny table lies beside the datasets, not beside the rig
  o.out = out;
  return o;
}

int run_cli(std::vector<std::string> args) {
  args.insert(args.begin(), "retarget");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  return cli::run(static_cast<int>(argv.size()), argv.data());
}

bool finite(const ExpressionErrorSum& s) {
  bool ok = std::isfinite(s.mean) && std::isfinite(s.moving_mean) && std::isfinite(s.max);
  for (const auto& [region, value] : s.region_mean) ok = ok && std::isfinite(value);
  return ok;
}

}  // namespace

TEST_CASE("error ladder: every rung on the tiny data, counts from the splits", "[error_ladder]") {
  const fs::path dir = scratch_dir("error_ladder_rungs");
  const ErrorLadder ladder = error_ladder(options_for((dir / "out").string()));
  const Dataset human = load_dataset(ladder_fixture().human_dataset);
  const Dataset avatar = load_dataset(ladder_fixture().avatar_dataset);
  const int64_t expressions = 4;  // neutral, A, AB, C: every one has a correspondence

  REQUIRE(ladder.rungs.size() == 8);
  const std::vector<std::string> keys{
      "avatar_vae_test", "avatar_vae_truth", "human_vae_test", "dt", "dt_rig", "y0", "f_train", "f_test"};
  const std::vector<int64_t> samples{static_cast<int64_t>(avatar.test.size()),
                                     expressions,
                                     static_cast<int64_t>(human.test.size()),
                                     expressions,
                                     expressions,
                                     expressions,
                                     static_cast<int64_t>(human.train.size()),
                                     static_cast<int64_t>(human.test.size())};
  CHECK(avatar.test.size() == 12);
  CHECK(human.train.size() == 6 * 4);
  CHECK(human.test.size() == 2 * 4);
  for (size_t i = 0; i < ladder.rungs.size(); ++i) {
    const LadderRung& r = ladder.rungs[i];
    INFO(r.name);
    CHECK(r.number == static_cast<int>(i) + 1);
    CHECK(r.key == keys[i]);
    CHECK(r.samples == samples[i]);
    CHECK(r.error.count == r.samples);
    CHECK(r.trivial_error.count == r.samples);
    CHECK(finite(r.error));
    CHECK(finite(r.trivial_error));
    CHECK(r.error.mean > 0);
    CHECK(r.trivial_error.mean > 0);
    CHECK(r.fraction == Approx(r.error.mean / r.trivial_error.mean));
    CHECK(r.moving_fraction == Approx(r.error.moving_mean / r.trivial_error.moving_mean));
    CHECK(r.side == (r.key == "human_vae_test" ? "human" : "avatar"));
    // Every rung but the random rig samples is broken down by expression.
    CHECK(r.expression_error.size() == (r.key == "avatar_vae_test" ? 0u : 4u));
  }
  // The avatar's regions come from the table's human shapes; the tiny ones (a, b, c) name none.
  CHECK(ladder.avatar_moving > 0);
  CHECK(ladder.avatar_moving <= ladder.avatar_vertices);
  CHECK(ladder.avatar_vertices == avatar.vertex_count());
  CHECK(ladder.human_vertices == human.vertex_count());
  // The avatar has eyes (mm); the tiny face model has none (mesh units).
  CHECK(ladder.rungs[0].unit == "mm");
  CHECK(ladder.rungs[2].unit == "units");
  // Rungs 2, 4, 5 and 6 score the same items, so their trivial answers agree.
  CHECK(ladder.rungs[3].trivial_error.mean == Approx(ladder.rungs[1].trivial_error.mean));
  CHECK(ladder.rungs[4].trivial_error.mean == Approx(ladder.rungs[1].trivial_error.mean));
  CHECK(ladder.rungs[5].trivial_error.mean == Approx(ladder.rungs[1].trivial_error.mean));
  // The neutral expression's truth is the rest itself.
  CHECK(ladder.rungs[1].expression_trivial.at("neutral").mean == Approx(0).margin(1e-9));

  // ladder.json: one entry per rung with the same figures.
  REQUIRE(ladder.json_path == (dir / "out" / "ladder.json").string());
  std::ifstream in(ladder.json_path);
  const nlohmann::json j = nlohmann::json::parse(in);
  CHECK(j["format"] == "retarget-error-ladder");
  REQUIRE(j["rungs"].size() == 8);
  for (size_t i = 0; i < 7; ++i) {
    const nlohmann::json& r = j["rungs"][i];
    CHECK(r["key"] == keys[i]);
    CHECK(r["samples"].get<int64_t>() == samples[i]);
    CHECK(r["error"]["mean"].get<double>() == Approx(ladder.rungs[i].error.mean));
    CHECK(r["trivial_error"]["moving_mean"].get<double>() == Approx(ladder.rungs[i].trivial_error.moving_mean));
    CHECK(r["fraction"].get<double>() == Approx(ladder.rungs[i].fraction));
  }
  CHECK(j["rungs"][1]["expressions"]["AB"]["samples"] == 1);

  const std::string table = ladder_table(ladder);
  for (const LadderRung& r : ladder.rungs) CHECK(table.find(r.name) != std::string::npos);
}

TEST_CASE("error ladder: the neutral answer on the ground-truth rung, by hand", "[error_ladder]") {
  const ErrorLadder ladder = error_ladder(options_for((scratch_dir("error_ladder_hand") / "out").string()));
  const Dataset avatar = load_dataset(ladder_fixture().avatar_dataset);
  const Rig rig = load_rig(avatar.source);
  const double mm = millimetres_per_unit(rig.neutral.vertices, rig.eyes);
  // The tiny table maps a -> ctrl0, b -> ctrl1, c -> ctrl2 one to one; the recipes are
  // neutral {}, A {a: 1}, AB {a: 0.5, b: 1}, C {c: 1}.
  std::vector<Eigen::VectorXd> weights(4, Eigen::VectorXd::Zero(4));
  weights[1](0) = 1.0;
  weights[2](0) = 0.5, weights[2](1) = 1.0;
  weights[3](2) = 1.0;
  double sum = 0;
  for (const Eigen::VectorXd& w : weights) {
    const Positions truth = rig.evaluate(w);
    const Positions rest = rigid_alignment(rig.neutral.vertices, truth).apply(rig.neutral.vertices);
    sum += (rest - truth).rowwise().norm().mean() * mm;
  }
  const LadderRung& rung = ladder.rungs[1];
  REQUIRE(rung.samples == 4);
  CHECK(rung.trivial_error.mean == Approx(sum / 4).epsilon(1e-9));
  CHECK(rung.trivial_error.mean > 0.1);  // the expressions do move the avatar

  // Regions come from the human shapes of each controller's table row: a table that also says
  // ctrl3 stands for jawOpen (which no recipe uses, so the truth stays the same) puts ctrl3's
  // vertices in the mouth region.
  const fs::path dir = scratch_dir("error_ladder_regions");
  const std::string table = (dir / "correspondence.yaml").string();
  write_controller_correspondence(
      table, {{"ctrl0", {{"a", 1.0}}}, {"ctrl1", {{"b", 1.0}}}, {"ctrl2", {{"c", 1.0}}}, {"ctrl3", {{"jawOpen", 1.0}}}},
      "blob");
  ErrorLadderOptions o = options_for((dir / "out").string());
  o.table = table;
  const ErrorLadder regions = error_ladder(o);
  REQUIRE(regions.avatar_regions.count("mouth") == 1);
  CHECK(regions.avatar_regions.at("mouth") > 0);
  CHECK(regions.rungs[1].trivial_error.mean == Approx(sum / 4).epsilon(1e-9));
  for (const LadderRung& r : regions.rungs) {
    if (r.side != "avatar") continue;
    INFO(r.name);
    REQUIRE(r.error.region_mean.count("mouth") == 1);
    CHECK(std::isfinite(r.error.region_mean.at("mouth")));
    CHECK(r.trivial_error.region_mean.at("mouth") > 0);
  }
}

TEST_CASE("error ladder: the command writes ladder.json; bad options name the option", "[error_ladder]") {
  const LadderFixture& f = ladder_fixture();
  const fs::path out = scratch_dir("error_ladder_command") / "ladder";
  CHECK(run_cli({"eval", "ladder", "--correspondences", f.correspondences, "--translation", f.translation,
                 "--checkpoint", "stage1", "--table", f.table, "--out", out.string()}) == 0);
  std::ifstream in(out / "ladder.json");
  REQUIRE(in.good());
  const nlohmann::json j = nlohmann::json::parse(in);
  CHECK(j["checkpoint"] == "stage1");
  CHECK(j["rungs"].size() == 8);

  ErrorLadderOptions o = options_for(out.string());
  o.correspondences.clear();
  CHECK_THAT(error_of([&] { error_ladder(o); }), Catch::Contains("--correspondences"));
  o.correspondences = (out / "no-such-folder").string();
  CHECK_THAT(error_of([&] { error_ladder(o); }),
             Catch::Contains("--correspondences") && Catch::Contains("no-such-folder"));
  o = options_for(out.string());
  o.translation.clear();
  CHECK_THAT(error_of([&] { error_ladder(o); }), Catch::Contains("--translation"));
  o = options_for(out.string());
  o.checkpoint = "best";
  CHECK_THAT(error_of([&] { error_ladder(o); }), Catch::Contains("--checkpoint"));
  o = options_for(out.string());
  o.checkpoint = "stage7";  // a stage the run does not have
  CHECK_THAT(error_of([&] { error_ladder(o); }), Catch::Contains("--checkpoint"));
  o = options_for(out.string());
  o.table = (out / "missing.yaml").string();
  CHECK_THAT(error_of([&] { error_ladder(o); }), Catch::Contains("--table"));
  // Without --table the default is correspondence.yaml beside the rig, which the tiny rig lacks.
  o = options_for(out.string());
  o.table.clear();
  CHECK_THAT(error_of([&] { error_ladder(o); }), Catch::Contains("correspondence.yaml") && Catch::Contains("--table"));
}

TEST_CASE(
    "error ladder: with a faces folder, rung 9 carries the unseen blends through F and rung 10 their truth "
    "through the avatar VAE",
    "[error_ladder]") {
  const fs::path dir = scratch_dir("error_ladder_blends");
  TestFacesOptions fo;
  fo.blends.count = 3;
  const TestFaces faces = write_test_faces(ladder_fixture().human_dataset, (dir / "faces").string(), fo);
  ErrorLadderOptions o = options_for((dir / "out").string());
  o.faces = (dir / "faces").string();
  const ErrorLadder ladder = error_ladder(o);
  REQUIRE(ladder.rungs.size() == 10);
  const LadderRung& r = ladder.rungs[8];
  CHECK(r.number == 9);
  CHECK(r.key == "f_blends");
  int blends = 0;
  for (const TestFace& f : faces.faces) blends += f.set == kBlendSet;
  CHECK(r.samples == blends);
  CHECK(r.expression_error.size() == 3u);  // blend000 .. blend002, over the people
  CHECK(finite(r.error));
  CHECK(r.trivial_error.mean > 0);
  // Rung 10: the same blends against the same truths (so the same trivial error), through the VAE.
  const LadderRung& v = ladder.rungs[9];
  CHECK(v.number == 10);
  CHECK(v.key == "avatar_vae_blends");
  CHECK(v.samples == blends);
  CHECK(v.expression_error.size() == 3u);
  CHECK(v.trivial_error.mean == Approx(r.trivial_error.mean));
  CHECK(finite(v.error));
  CHECK(v.error.mean != Approx(r.error.mean));
  // A folder without blends is named.
  fo.blends.count = 0;
  fo.force = true;
  write_test_faces(ladder_fixture().human_dataset, (dir / "faces").string(), fo);
  CHECK_THROWS_WITH(error_ladder(o), Catch::Contains("has no blends"));
}
