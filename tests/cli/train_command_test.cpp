// `retarget train PROFILE --out RUN`: a profile of configs/train (a base plus what it changes)
// with the run's files from the command line.
#include <catch2/catch.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "core/error.h"
#include "run_command.h"
#include "test_support.h"
#include "tiny_data.h"
#include "train/train_config.h"
#include "train/vae_config.h"

using namespace retarget;
using namespace retarget::test;
using Catch::Contains;
namespace fs = std::filesystem;

namespace {

int run_train(std::vector<std::string> args, std::string* printed = nullptr) {
  return run_command(cli::train_command, "train", std::move(args), printed);
}

std::string profile(const std::string& relative) {
  return (fs::path(RETARGET_SOURCE_DIR) / "configs/train" / relative).string();
}

}  // namespace

TEST_CASE("retarget train PROFILE --out RUN trains the merged profile into RUN", "[train_command]") {
  const std::string dataset = build_tiny_avatar_dataset("train_command_avatar", tiny_rig(7), 60, 0.2, 2);
  // --out is taken as it is, not read as YAML (this one would be a list and a comment).
  const fs::path run = scratch_dir("train_command_out") / "[run]: #1";
  std::string printed;
  REQUIRE(run_train({profile("quick/avatar_vae.yaml"), "--set", "data.dataset=" + dataset, "--out", run.string(),
                     "--set", "training.epochs=1", "--set", "training.threads=1"},
                    &printed) == 0);
  CHECK_THAT(printed, Contains(run.string() + ": 1 epochs"));
  CHECK(fs::exists(run / "checkpoints" / "last.pt"));
  // The run's own config: the quick profile's values over the paper base's, the --set and --out.
  const VaeTrainConfig written = read_vae_train_config(load_config_with_overrides((run / "config.yaml").string(), {}));
  CHECK(written.output == run.string());
  CHECK(written.model.channels() == std::vector<int64_t>{9, 32, 16, 16, 16, 1});  // quick's
  CHECK(written.model.hidden() == 300);                                           // the base's
  CHECK(written.reconstruction == ReconstructionLoss::squared);
  CHECK(written.optimiser.lr == 3e-4);
  CHECK(written.schedule.decay == 0.6);  // the base's
  CHECK(written.schedule.every == 3);    // quick's
  CHECK(written.training.batch_size == 30);
  CHECK(written.training.epochs == 1);  // --set
  // The run folder alone names the run again: its config.yaml holds the output.
  CHECK_THAT(error_of([&] {
               run_train({run.string(), "--resume"});
             }),
             Contains(run.string() + ": the run finished (1 epochs); nothing to resume"));
}

TEST_CASE("retarget train: the run folder is required, given once, by --out or --set output=", "[train_command]") {
  const std::string avatar = profile("quick/avatar_vae.yaml");
  CHECK_THAT(error_of([&] {
               run_train({profile("quick/human_vae.yaml"), "--set", "data.dataset=ds"});
             }),
             Contains("quick/human_vae.yaml: output: missing: the run folder; give it with `retarget train CONFIG "
                      "--out DIR` (or --set output=DIR)"));
  CHECK(error_of([&] {
          run_train({avatar, "--out", "a", "--set", "output=b"});
        }) == "retarget train: --out and --set output=b both name the run folder; give one");
  CHECK(error_of([&] { run_train({avatar, "--out", ""}); }) == "--out: expected a run folder, got \"\"");
  CHECK_THAT(error_of([&] {
               run_train({avatar, "--out", "runs/x"});
             }),
             Contains("quick/avatar_vae.yaml: data.dataset: missing: the dataset folder") &&
                 Contains("give it with --set data.dataset=PATH"));
  CHECK_THAT(error_of([&] {
               run_train({profile("quick/translation.yaml"), "--out", "runs/x"});
             }),
             Contains("quick/translation.yaml: data.human_vae: missing: the human VAE's run folder"));
}
