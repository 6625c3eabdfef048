#include "train/checkpoint.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "child_process.h"
#include "core/error.h"
#include "test_support.h"
#include "tiny_data.h"
#include "train/run_folder.h"

using namespace retarget;
using namespace retarget::test;
namespace fs = std::filesystem;

TEST_CASE("every field of a checkpoint's state round-trips, whatever its type", "[checkpoint]") {
  const fs::path dir = scratch_dir("checkpoint_state");
  torch::nn::Linear module(3, 2);
  torch::optim::Adam optimiser(module->parameters(), torch::optim::AdamOptions(1e-2));
  const CheckpointState states[] = {{3, 0, 0.00642}, {1, -1, 0}, {250000, 249999, 4.25e-9}, {7, 2, 1e12}};
  for (const CheckpointState& state : states) {
    const std::string path = (dir / "c.pt").string();
    save_checkpoint(path, *module, &optimiser, state);
    torch::nn::Linear other(3, 2);
    torch::optim::Adam other_optimiser(other->parameters(), torch::optim::AdamOptions(1e-2));
    const CheckpointState back = load_checkpoint(path, *other, &other_optimiser, "test");
    CHECK(back.epoch == state.epoch);
    CHECK(back.best_epoch == state.best_epoch);
    CHECK(back.best_validation == state.best_validation);  // bit for bit
    const CheckpointState alone = read_checkpoint_state(path);
    CHECK(alone.epoch == state.epoch);
    CHECK(alone.best_epoch == state.best_epoch);
    CHECK(alone.best_validation == state.best_validation);
    CHECK(torch::equal(other->weight, module->weight));
    CHECK(torch::equal(other->bias, module->bias));
  }
}

TEST_CASE("a checkpoint whose state is not a finite number is refused, naming the field", "[checkpoint]") {
  const fs::path dir = scratch_dir("checkpoint_bad_state");
  torch::nn::Linear module(2, 1);
  const std::string path = (dir / "c.pt").string();
  save_checkpoint(path, *module, nullptr, {2, 1, std::nan("")});
  CHECK(error_of([&] { read_checkpoint_state(path); }) ==
        path + ": state 'best_validation' is nan, expected a finite number");
  CHECK_THAT(error_of([&] { read_checkpoint_state((dir / "none.pt").string()); }),
             Catch::Contains("no such checkpoint"));
}

TEST_CASE("a run killed while its untrained start is the best resumes without losing that model",
          "[checkpoint][slow]") {
  const fs::path dir = scratch_dir("checkpoint_killed");
  // Epochs long enough (about 250 ms here, polled every 2 ms) that the kill lands inside epoch 2.
  const std::string dataset = build_tiny_avatar_dataset("checkpoint_killed_data", tiny_rig(7), 1500, 0.2, 3);
  const fs::path run = dir / "run";
  const fs::path config = dir / "c.yaml";
  // The principal start (with the encoder skip) is a fitted model already; a KL weight of 1 pulls
  // every epoch's codes to the prior and its reconstructions far off, so the start stays the best.
  std::ofstream(config) << "task: vae\n"
                           "data: {dataset: "
                        << dataset
                        << ", validation_fraction: 0.2}\n"
                           "model: {channels: [9, 16, 16, 1], hidden: 64, latent: 4, order: 2, decoder_start: "
                           "principal, encoder_skip: true}\n"
                           "loss: {kl_weight: 1.0}\n"
                           "optimiser: {lr: 0.01}\n"
                           "training: {epochs: 4, batch_size: 4, checkpoint_every: 1, seed: 7, threads: 1}\n"
                           "output: "
                        << run.string() << "\n";
  const pid_t child = spawn_retarget({"train", config.string()}, dir / "first.log");
  REQUIRE(child > 0);
  // Kill -9 as soon as epoch 1's checkpoint is recorded in run.yaml (epoch 2 running).
  bool killed = false;
  for (int i = 0; i < 60000 && !killed; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    std::error_code ec;
    if (fs::exists(run / "run.yaml", ec) && RunStatus::load(run.string()).epochs_done >= 1) {
      ::kill(child, SIGKILL);
      killed = true;
    }
    int status = 0;
    if (!killed && ::waitpid(child, &status, WNOHANG) == child) break;  // ended on its own: fails below
  }
  REQUIRE(killed);
  CHECK(WIFSIGNALED(wait_for(child)));
  const RunStatus before = RunStatus::load(run.string());
  REQUIRE(before.epochs_done == 1);  // the kill landed in epoch 2
  REQUIRE(before.best_epoch == 0);   // the untrained start is the best so far
  const fs::path best = run / "checkpoints" / "best.pt";
  const std::string best_bytes = file_bytes(best);
  const CheckpointState saved = read_checkpoint_state(best.string());
  CHECK(saved.best_epoch == 0);

  const pid_t resumed = spawn_retarget({"train", run.string(), "--resume"}, dir / "resumed.log");
  const int status = wait_for(resumed);
  INFO(file_bytes(dir / "resumed.log"));
  REQUIRE(WIFEXITED(status));
  REQUIRE(WEXITSTATUS(status) == 0);
  const RunStatus after = RunStatus::load(run.string());
  CHECK(after.status == "finished");
  CHECK(after.epochs_done == 4);
  CHECK(after.best_epoch == 0);
  CHECK(after.best_validation == Approx(saved.best_validation).epsilon(1e-9));
  CHECK(file_bytes(best) == best_bytes);  // the start's weights, untouched
  for (const auto& row : read_metrics(run.string())) CHECK(row.at("validation_l1") > saved.best_validation);
}
