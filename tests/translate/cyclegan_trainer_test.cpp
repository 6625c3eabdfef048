#include "translate/cyclegan_trainer.h"

#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "bundle/bundle_format.h"
#include "cli/commands.h"
#include "core/config.h"
#include "core/error.h"
#include "run_command.h"
#include "scratch.h"
#include "tiny_correspondence.h"
#include "tiny_vae_runs.h"
#include "train/run_folder.h"
#include "train/vae_run.h"
#include "translate/cyclegan_config.h"
#include "translate/cyclegan_run.h"

using namespace retarget;
using namespace retarget::test;
namespace fs = std::filesystem;

namespace {

// The tiny human and avatar datasets (tests/tiny_correspondence.h) with a VAE each.
struct CycleGanFixture {
  std::string human_vae, avatar_vae;
};

const CycleGanFixture& gan_fixture() {
  static const CycleGanFixture f = [] {
    const TinyCorrespondenceData& data = tiny_correspondence_data();
    const fs::path dir = process_scratch_dir("cyclegan_fixture");
    CycleGanFixture t;
    t.human_vae = (dir / "human_vae").string();
    train_tiny_vae(tiny_vae_config(data.human, t.human_vae, 3, 11));
    t.avatar_vae = (dir / "avatar_vae").string();
    train_tiny_vae(tiny_vae_config(data.avatar, t.avatar_vae, 4, 7));
    return t;
  }();
  return f;
}

std::string gan_config_text(const std::string& output, int epochs = 30) {
  return "task: cyclegan\n"
         "data: {human_vae: " +
         gan_fixture().human_vae + ", avatar_vae: " + gan_fixture().avatar_vae +
         "}\n"
         "light_field: {samples: 12, size: 32}\n"
         "model: {hidden: 16, critic_hidden: 16}\n"
         "similarity: {epochs: 20, lr: 1.0e-2, batch_size: 32}\n"
         "optimiser: {lr: 2.0e-3}\n"
         "training: {epochs: " +
         std::to_string(epochs) + ", batch_size: 8, checkpoint_every: 5, seed: 4, threads: 1}\noutput: " + output +
         "\n";
}

CycleGanTrainConfig gan_config(const std::string& output, int epochs = 30) {
  return read_cyclegan_train_config(ConfigNode::parse(gan_config_text(output, epochs), "cyclegan.yaml"));
}

CycleGanTrainOptions gan_quiet(RunStart start = RunStart::fresh, int stop_after = -1) {
  CycleGanTrainOptions o;
  o.progress = nullptr;
  o.start = start;
  o.stop_after_epochs = stop_after;
  return o;
}

// G's avatar codes for every human training code of the fixture.
torch::Tensor gan_translated(const std::string& run) {
  TrainedCycleGan trained = load_trained_cyclegan(run);
  TrainedVae human = load_trained_vae(gan_fixture().human_vae, "best");
  const torch::Tensor x = encoder_means(human, human.dataset.features);
  torch::NoGradGuard no_grad;
  return trained.net->to_avatar->forward(x);
}

}  // namespace

TEST_CASE("the CycleGAN's cycle loss falls as its generators learn to invert each other", "[translate][cyclegan]") {
  const fs::path dir = scratch_dir("cyclegan_cycle");
  const CycleGanTrainSummary s = train_cyclegan(gan_config((dir / "run").string()), gan_quiet());
  REQUIRE(s.finished);
  CHECK(s.epochs_done == 30);
  CHECK(s.human_codes == 6 * 4);  // the tiny human dataset's training people x 4 expressions
  INFO("cycle " << s.first.cycle << " -> " << s.last.cycle);
  CHECK(s.last.cycle < 0.5 * s.first.cycle);
  CHECK(std::isfinite(s.last.adversarial));
  CHECK(s.last.similarity > 0);
  CHECK(s.last.similarity < 1);
  // The similarity regressor's fit is on record beside the trivial answer, in the run folder.
  CHECK(s.fit.pairs == 12 * 12);
  CHECK(s.fit.held_out_pairs == 14);
  CHECK(std::isfinite(s.fit.held_out_mse));
  CHECK(s.fit.held_out_mean_mse > 0);
  const ConfigNode fit = ConfigNode::load_file((dir / "run/similarity.yaml").string());
  CHECK(fit.child("pairs").as<int>() == 144);
  CHECK(RunStatus::load((dir / "run").string()).task == "cyclegan");
  std::ifstream csv(dir / "run/metrics.csv");
  std::string header;
  std::getline(csv, header);
  CHECK(header == "epoch,generator,adversarial,cycle,cycle_human,cycle_avatar,similarity,discriminator,seconds");
}

TEST_CASE("a CycleGAN run resumed mid-way ends with the weights of one never interrupted", "[translate][cyclegan]") {
  const fs::path dir = scratch_dir("cyclegan_resume");
  train_cyclegan(gan_config((dir / "whole").string(), 12), gan_quiet());
  const CycleGanTrainSummary part =
      train_cyclegan(gan_config((dir / "parts").string(), 12), gan_quiet(RunStart::fresh, 7));
  CHECK(!part.finished);
  CHECK(part.epochs_done == 7);
  const CycleGanTrainSummary rest =
      train_cyclegan(gan_config((dir / "parts").string(), 12), gan_quiet(RunStart::resume));
  CHECK(rest.finished);
  CHECK(rest.epochs_run == 7);  // back to the checkpoint of epoch 5, then 6 .. 12
  CHECK(rest.fit.pairs == part.fit.pairs);
  CHECK(torch::equal(gan_translated((dir / "whole").string()), gan_translated((dir / "parts").string())));
}

TEST_CASE("a CycleGAN run exports as a bundle that computes encoder, generator, decoder", "[translate][cyclegan]") {
  const fs::path dir = scratch_dir("cyclegan_export");
  train_cyclegan(gan_config((dir / "run").string(), 3), gan_quiet());
  REQUIRE(run_command(cli::export_command, "export", {(dir / "run").string(), "--out", (dir / "bundle").string()}) ==
          0);
  const LoadedBundle bundle = load_bundle((dir / "bundle").string());
  TrainedVae human = load_trained_vae(gan_fixture().human_vae, "best");
  TrainedVae avatar = load_trained_vae(gan_fixture().avatar_vae, "best");
  TrainedCycleGan trained = load_trained_cyclegan((dir / "run").string());
  const torch::Tensor x = human.dataset.features.index_select(0, torch::tensor(human.dataset.test));
  torch::NoGradGuard no_grad;
  const torch::Tensor code = human.vae->encode(human.dataset.normaliser.normalise(x)).mean;
  const torch::Tensor expected =
      avatar.dataset.normaliser.denormalise(avatar.vae->decode(trained.net->to_avatar->forward(code)));
  torch::jit::Module module = bundle.module;
  const torch::Tensor y = module.forward({x}).toTensor();
  REQUIRE(y.sizes() == expected.sizes());
  CHECK((y - expected).abs().max().item<double>() < 1e-4);
  CHECK_THROWS_WITH(run_command(cli::export_command, "export", {(dir / "run").string(), "--lec"}),
                    Catch::Contains("'cyclegan' run"));
}

TEST_CASE("a bad CycleGAN config is refused naming the key", "[translate][cyclegan]") {
  auto error_of = [](const std::string& text) -> std::string {
    try {
      read_cyclegan_train_config(ConfigNode::parse(text, "cg.yaml"));
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  const std::string base = "task: cyclegan\ndata: {human_vae: h, avatar_vae: a}\noutput: o\n";
  CHECK(error_of(base).empty());
  CHECK_THAT(error_of(base + "light_field: {samples: 1}\n"), Catch::Contains("light_field.samples"));
  CHECK_THAT(error_of(base + "light_field: {size: 8}\n"), Catch::Contains("light_field.size"));
  CHECK_THAT(error_of(base + "loss: {cycle: -1}\n"), Catch::Contains("loss.cycle"));
  CHECK_THAT(error_of(base + "optimiser: {lr: 0}\n"), Catch::Contains("optimiser.lr"));
  CHECK_THAT(error_of(base + "loss: {cycles: 1}\n"), Catch::Contains("cycles"));
  CHECK_THAT(error_of("task: cyclegan\ndata: {avatar_vae: a}\noutput: o\n"),
             Catch::Contains("data.human_vae: missing"));
  CHECK_THAT(error_of("task: cyclegan\ndata: {human_vae: h, avatar_vae: a, human_checkpoint: first}\noutput: o\n"),
             Catch::Contains("data.human_checkpoint"));
}
