#include "train/data_parallel.h"

#include <signal.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "child_process.h"
#include "core/cpu_threads.h"
#include "scratch.h"
#include "tiny_correspondence.h"
#include "tiny_vae_runs.h"
#include "train/run_folder.h"
#include "train/train_config.h"
#include "train/vae_run.h"
#include "train/vae_trainer.h"

using namespace retarget;
using namespace retarget::test;
namespace fs = std::filesystem;

namespace {

// The tiny avatar dataset's VAE config (tests/tiny_vae_runs.h) with `epochs` epochs, as a file.
std::string dp_config(const fs::path& dir, int epochs, int batch = 4) {
  std::string text = tiny_vae_config(tiny_correspondence_data().avatar, "unused", 4, 7);
  text.replace(text.find("epochs: 3"), 9, "epochs: " + std::to_string(epochs));
  text.replace(text.find("batch_size: 4"), 13, "batch_size: " + std::to_string(batch));
  const fs::path file = dir / ("vae" + std::to_string(epochs) + "_" + std::to_string(batch) + ".yaml");
  std::ofstream(file) << text;
  return file.string();
}

// How far two runs that take the same steps may end apart: the ranks sum a step's gradients in
// another order (each rank its part, then the parts), and the CPU's kernels round each order their
// own way (1.09e-5 apart on an Intel Xeon with AMX, under 1e-5 on an AMD EPYC).
constexpr double rounding = 5e-5;

// The largest difference between the two runs' weights in checkpoints/last.pt.
double weight_difference(const fs::path& a, const fs::path& b) {
  const TrainedVae x = load_trained_vae(a.string(), "last"), y = load_trained_vae(b.string(), "last");
  double largest = 0;
  const auto px = x.vae->named_parameters(), py = y.vae->named_parameters();
  for (const auto& p : px) largest = std::max(largest, (p.value() - py[p.key()]).abs().max().item<double>());
  return largest;
}

int exit_code(pid_t child) {
  const int status = wait_for(child);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::vector<std::string> rank_env(int rank, int port, int timeout_seconds) {
  return {"WORLD_SIZE=2",
          "RANK=" + std::to_string(rank),
          "LOCAL_RANK=" + std::to_string(rank),
          "LOCAL_WORLD_SIZE=2",
          "MASTER_ADDR=127.0.0.1",
          "MASTER_PORT=" + std::to_string(port),
          "RETARGET_DIST_TIMEOUT=" + std::to_string(timeout_seconds)};
}

}  // namespace

TEST_CASE("data-parallel: two ranks on one global batch end with the weights of one rank", "[train][parallel]") {
  const fs::path dir = scratch_dir("dp_same_weights");
  const std::string config = dp_config(dir, 3);
  REQUIRE(exit_code(spawn_retarget({"train", config, "--out", (dir / "one").string()}, dir / "one.log")) == 0);
  REQUIRE(exit_code(spawn_retarget({"train", config, "--out", (dir / "two").string(), "--nproc", "2"},
                                   dir / "two.log")) == 0);
  INFO(file_bytes(dir / "two.log"));
  CHECK(weight_difference(dir / "one", dir / "two") < rounding);
  // Another batch size trains another model, far further apart than rounding.
  REQUIRE(exit_code(spawn_retarget({"train", dp_config(dir, 3, 2), "--out", (dir / "one_batch2").string()},
                                   dir / "one_batch2.log")) == 0);
  CHECK(weight_difference(dir / "one", dir / "one_batch2") > 100 * rounding);
  CHECK(read_metrics((dir / "two").string()).size() == 3);  // rank 0 alone logged, once per epoch
  CHECK(RunStatus::load((dir / "two").string()).status == "finished");

  // Batches of one row: rank 1's part is empty at every step (no backward); it still sends its
  // zeros, and the weights are still one rank's. Three ranks: parts of 1, 1 and 0 or 1 rows.
  const std::string single = dp_config(dir, 1, 1);
  REQUIRE(exit_code(spawn_retarget({"train", single, "--out", (dir / "one_b1").string()}, dir / "one_b1.log")) == 0);
  REQUIRE(exit_code(spawn_retarget({"train", single, "--out", (dir / "two_b1").string(), "--nproc", "2"},
                                   dir / "two_b1.log")) == 0);
  CHECK(weight_difference(dir / "one_b1", dir / "two_b1") < rounding);
  CHECK_THAT(file_bytes(dir / "two_b1.log"), Catch::Contains("training.batch_size is 1 rows for 2 ranks"));
  const std::string odd = dp_config(dir, 1, 5);
  REQUIRE(exit_code(spawn_retarget({"train", odd, "--out", (dir / "one_b5").string()}, dir / "one_b5.log")) == 0);
  REQUIRE(exit_code(spawn_retarget({"train", odd, "--out", (dir / "three_b5").string(), "--nproc", "3"},
                                   dir / "three_b5.log")) == 0);
  CHECK(weight_difference(dir / "one_b5", dir / "three_b5") < rounding);
}

TEST_CASE("data-parallel: a run resumes with another number of ranks", "[train][parallel]") {
  const fs::path dir = scratch_dir("dp_resume");
  const std::string config = dp_config(dir, 4);
  REQUIRE(exit_code(spawn_retarget({"train", config, "--out", (dir / "whole").string()}, dir / "whole.log")) == 0);
  // One rank for two epochs (stopped as if killed), then two ranks to the end.
  VaeTrainOptions partial;
  partial.progress = nullptr;
  partial.stop_after_epochs = 2;
  VaeTrainConfig c = read_vae_train_config(load_config_with_overrides(config, {"output=" + (dir / "parts").string()}));
  REQUIRE(!train_vae(c, partial).finished);
  REQUIRE(RunStatus::load((dir / "parts").string()).epochs_done == 2);
  REQUIRE(exit_code(spawn_retarget({"train", (dir / "parts").string(), "--resume", "--nproc", "2"},
                                   dir / "second.log")) == 0);
  INFO(file_bytes(dir / "second.log"));
  CHECK_THAT(file_bytes(dir / "second.log"), Catch::Contains("resuming"));
  CHECK(RunStatus::load((dir / "parts").string()).status == "finished");
  CHECK(read_metrics((dir / "parts").string()).size() == 4);
  CHECK(weight_difference(dir / "whole", dir / "parts") < rounding);
}

TEST_CASE("data-parallel: a rank that never arrives ends the others with a clear error", "[train][parallel]") {
  const fs::path dir = scratch_dir("dp_missing_rank");
  const std::string config = dp_config(dir, 3);
  const auto started = std::chrono::steady_clock::now();
  const pid_t alone = spawn_retarget({"train", config, "--out", (dir / "run").string()},
                                     rank_env(0, free_loopback_port(), 3), dir / "rank0.log");
  CHECK(exit_code(alone) != 0);
  CHECK(std::chrono::steady_clock::now() - started < std::chrono::seconds(60));
  CHECK_THAT(file_bytes(dir / "rank0.log"),
             Catch::Contains("data-parallel rank 0 of 2") && Catch::Contains("did not answer within 3 s"));
}

TEST_CASE("data-parallel: a killed rank ends the others with a clear error", "[train][parallel]") {
  const fs::path dir = scratch_dir("dp_killed_rank");
  const std::string config = dp_config(dir, 400);
  const int port = free_loopback_port();
  const pid_t rank0 =
      spawn_retarget({"train", config, "--out", (dir / "run").string()}, rank_env(0, port, 30), dir / "rank0.log");
  const pid_t rank1 =
      spawn_retarget({"train", config, "--out", (dir / "run").string()}, rank_env(1, port, 30), dir / "rank1.log");
  const fs::path metrics = dir / "run/metrics.jsonl";
  for (int i = 0; i < 6000 && !fs::exists(metrics); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  REQUIRE(fs::exists(metrics));  // training under way
  ::kill(rank1, SIGKILL);
  wait_for(rank1);
  const auto killed = std::chrono::steady_clock::now();
  CHECK(exit_code(rank0) != 0);
  CHECK(std::chrono::steady_clock::now() - killed < std::chrono::seconds(45));
  CHECK_THAT(file_bytes(dir / "rank0.log"), Catch::Contains("another rank stopped"));
}

TEST_CASE("data-parallel: the launcher reports a failed worker and stops the others", "[train][parallel]") {
  const fs::path dir = scratch_dir("dp_launcher_failure");
  // A dataset that is not there: every worker fails; the launcher names a rank.
  std::ofstream(dir / "bad.yaml") << "task: vae\ndata: {dataset: " << (dir / "missing").string() << "}\n";
  const pid_t launcher = spawn_retarget(
      {"train", (dir / "bad.yaml").string(), "--out", (dir / "run").string(), "--nproc", "2"}, dir / "launcher.log");
  CHECK(exit_code(launcher) != 0);
  CHECK_THAT(file_bytes(dir / "launcher.log"), Catch::Contains("worker rank") && Catch::Contains("of 2"));
  CHECK_THAT(file_bytes(dir / "launcher.log"), Catch::Contains("--resume"));
}

TEST_CASE("data-parallel: a killed launcher takes its workers with it, and the run resumes", "[train][parallel]") {
  const fs::path dir = scratch_dir("dp_killed_launcher");
  const std::string config = dp_config(dir, 60);
  const fs::path run = dir / "run";
  ::unsetenv("OMP_NUM_THREADS");
  const pid_t launcher = spawn_retarget({"train", config, "--out", run.string(), "--nproc", "2"}, dir / "launcher.log");
  const fs::path last = run / "checkpoints/last.pt";
  for (int i = 0; i < 6000 && !fs::exists(last); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  REQUIRE(fs::exists(last));
  // The processes naming the run folder: the launcher and its workers.
  auto processes = [&] {
    std::vector<fs::path> found;
    for (const auto& entry : fs::directory_iterator("/proc"))
      if (file_bytes(entry.path() / "cmdline").find(run.string()) != std::string::npos) found.push_back(entry.path());
    return found;
  };
  // The workers share the cores: the launcher gave each OMP_NUM_THREADS = the CPUs / 2.
  const std::string share = "OMP_NUM_THREADS=" + std::to_string(std::max(1, available_cpus() / 2));
  int workers = 0;
  for (const fs::path& p : processes()) {
    std::string environ_text = file_bytes(p / "environ");
    if (environ_text.find("WORLD_SIZE=2") == std::string::npos) continue;  // the launcher
    ++workers;
    for (char& c : environ_text)
      if (c == '\0') c = '\n';
    CHECK_THAT(environ_text + "\n", Catch::Contains("\n" + share + "\n"));
  }
  CHECK(workers == 2);
  ::kill(launcher, SIGKILL);
  wait_for(launcher);
  // No worker is left writing the run folder: every process naming it is gone within seconds.
  for (int i = 0; i < 100 && !processes().empty(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  CHECK(processes().empty());
  INFO(file_bytes(dir / "launcher.log"));
  REQUIRE(RunStatus::load(run.string()).status != "finished");  // killed after its first epochs of 60
  REQUIRE(exit_code(spawn_retarget({"train", run.string(), "--resume"}, dir / "resume.log")) == 0);
  CHECK_THAT(file_bytes(dir / "resume.log"), Catch::Contains("resuming"));
  CHECK(RunStatus::load(run.string()).status == "finished");
  CHECK(read_metrics(run.string()).size() == 60);
}
