// Training that says when it fails: the trivial answers' validation L1 beside the VAE's, and
// the warnings of runs that do not beat them or stop improving early (train/vae_trainer.h).
#include "train/vae_trainer.h"

// Catch after the LibTorch headers: glog, which they include, defines CHECK too.
#include <catch2/catch.hpp>
#include <filesystem>

#include "data/dataset.h"
#include "eval/vae_evaluation.h"
#include "test_support.h"
#include "tests/train/vae_train_options.h"
#include "tiny_data.h"
#include "train/train_config.h"
#include "train/vae_run.h"

using namespace retarget;
using namespace retarget::test;
namespace fs = std::filesystem;

namespace {

// A 64-vertex avatar dataset of 60 rig samples (built once per test binary).
std::string warnings_avatar_dataset() {
  static const std::string folder = build_tiny_avatar_dataset("vae_warnings_avatar_data", tiny_rig(7), 60, 0.2, 2);
  return folder;
}

VaeTrainConfig config_for(const std::string& output, int epochs, const std::string& lr) {
  const std::string text =
      "task: vae\n"
      "data: {dataset: " +
      warnings_avatar_dataset() +
      ", validation_fraction: 0.2}\n"
      "model: {channels: [9, 8, 4, 1], hidden: 32, latent: 4, order: 2}\n"
      "loss: {kl_weight: 1.0e-4}\n"
      "optimiser: {lr: " +
      lr +
      "}\n"
      "schedule: {decay: 0.6, every: 15}\n"
      "training: {epochs: " +
      std::to_string(epochs) +
      ", batch_size: 10, checkpoint_every: 1, seed: 7, threads: 1}\n"
      "output: " +
      output + "\n";
  return read_vae_train_config(ConfigNode::parse(text, "test.yaml"));
}

bool mentions(const std::vector<std::string>& warnings, const std::string& text) {
  for (const std::string& w : warnings)
    if (w.find(text) != std::string::npos) return true;
  return false;
}

}  // namespace

TEST_CASE("a VAE run that learns nothing says it does not beat the trivial answer", "[vae_trainer][baselines]") {
  const fs::path out = scratch_dir("vae_warnings_useless") / "run";
  // A learning rate so small that the weights stay where they were initialised.
  const VaeTrainSummary s = train_vae(config_for(out.string(), 2, "1.0e-12"), quiet());
  REQUIRE(s.finished);
  REQUIRE(s.baselines.count("neutral") == 1);
  REQUIRE(s.baselines.count("mean") == 1);
  CHECK(s.baselines.at("neutral") > 0);
  CHECK(s.baselines.at("mean") > 0);
  CHECK(mentions(s.warnings, "does not beat the trivial answer: validation L1 "));

  const RunStatus status = RunStatus::load(out.string());
  CHECK(status.warnings == s.warnings);
  CHECK(status.baselines.at("neutral") == Approx(s.baselines.at("neutral")).epsilon(1e-9));
  CHECK(status.baselines.at("mean") == Approx(s.baselines.at("mean")).epsilon(1e-9));
  const auto metrics = read_metrics(out.string());
  REQUIRE(metrics.size() == 2);
  for (const auto& row : metrics) {
    CHECK(row.at("neutral_validation_l1") == Approx(s.baselines.at("neutral")));
    CHECK(row.at("mean_validation_l1") == Approx(s.baselines.at("mean")));
  }
}

TEST_CASE("a resumed run gets its warnings when it finishes", "[vae_trainer][baselines]") {
  const fs::path out = scratch_dir("vae_warnings_resumed") / "run";
  const VaeTrainConfig config = config_for(out.string(), 2, "1.0e-12");
  const VaeTrainSummary first = train_vae(config, quiet(RunStart::fresh, 1));
  REQUIRE_FALSE(first.finished);
  CHECK(first.warnings.empty());  // judged only at the end
  const RunStatus unfinished = RunStatus::load(out.string());
  CHECK(unfinished.warnings.empty());
  CHECK(unfinished.baselines.count("neutral") == 1);
  const VaeTrainSummary second = train_vae(config, quiet(RunStart::resume));
  REQUIRE(second.finished);
  REQUIRE(second.warnings.size() == 1);
  CHECK(mentions(second.warnings, "does not beat the trivial answer"));
  CHECK(RunStatus::load(out.string()).warnings == second.warnings);
  CHECK(second.baselines == first.baselines);
}

TEST_CASE("a VAE run that learns gets no warning and beats its trivial answers", "[vae_trainer][baselines]") {
  const fs::path out = scratch_dir("vae_warnings_learns") / "run";
  // 40 epochs of ~10 ms; 8 are not enough to beat the mean answer on this dataset.
  const VaeTrainSummary s = train_vae(config_for(out.string(), 40, "1.0e-2"), quiet());
  REQUIRE(s.finished);
  CHECK(s.warnings.empty());
  CHECK(s.best_validation < 0.9 * s.baselines.at("neutral"));
  CHECK(s.best_validation < 0.9 * s.baselines.at("mean"));
  CHECK(RunStatus::load(out.string()).warnings.empty());
  // In mm too: the trained VAE beats the neutral mesh, over every vertex and the moving ones.
  TrainedVae trained = load_trained_vae(out.string(), "best");
  const VaeEvaluation e = evaluate_vae(*trained.vae, trained.dataset);
  CHECK(e.fraction_of_neutral < 1);
  CHECK(e.moving_fraction_of_neutral < 1);
}

TEST_CASE("training warnings: not beating the trivial answer, stopping early", "[vae_trainer][baselines]") {
  const std::map<std::string, double> baselines = {{"neutral", 0.0454}, {"mean", 0.05}};
  struct Row {
    double best;
    int best_epoch, done, planned;
    std::vector<std::string> expected;
  };
  const std::vector<Row> table = {
      {0.0445, 20, 30, 30, {"does not beat the trivial answer: validation L1 0.04450 vs neutral 0.04540 (x0.98)"}},
      {0.0409, 20, 30, 30, {"does not beat the trivial answer: validation L1 0.04090 vs neutral 0.04540 (x0.90)"}},
      {0.0400, 20, 30, 30, {}},
      {0.0100, 2, 30, 30, {"stopped improving after epoch 2 of 30"}},
      {0.0100, 7, 30, 30, {"stopped improving after epoch 7 of 30"}},  // 7 <= 25% of 30
      {0.0100, 8, 30, 30, {}},
      {0.0100, 2, 7, 7, {}},  // too few epochs to tell
      {0.0100, 2, 8, 8, {"stopped improving after epoch 2 of 8"}},
      {0.0100, 0, 10, 10, {"stopped improving after epoch 0 of 10 (no epoch beat the principal start)"}},
      {0.0450, 0, 3, 10, {"does not beat the trivial answer: validation L1 0.04500 vs neutral 0.04540 (x0.99)"}},
      {0.0450, -1, 0, 10, {}},  // nothing trained or scored
      {0.0500,
       1,
       10,
       10,
       {"does not beat the trivial answer: validation L1 0.05000 vs neutral 0.04540 (x1.10)",
        "stopped improving after epoch 1 of 10"}},
  };
  for (const Row& row : table) {
    INFO("best " << row.best << " at epoch " << row.best_epoch << " of " << row.done);
    CHECK(vae_training_warnings(row.best, row.best_epoch, row.done, row.planned, baselines) == row.expected);
  }
  // No baselines (a run.yaml from before them): nothing to compare with.
  CHECK(vae_training_warnings(1.0, 20, 30, 30, {}).empty());
  CHECK_THAT(trivial_answer_advice(ReconstructionLoss::l1), Catch::Contains("try loss.reconstruction: squared"));
  CHECK_THAT(trivial_answer_advice(ReconstructionLoss::squared), Catch::Contains("retarget eval vae"));
}
