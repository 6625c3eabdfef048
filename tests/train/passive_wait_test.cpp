// core/passive_wait.h through the real executable: `retarget` restarts itself with OpenMP's
// passive wait unless the user chose a policy.
#include <signal.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "child_process.h"
#include "scratch.h"
#include "train/data_parallel.h"

using namespace retarget;
using namespace retarget::test;
namespace fs = std::filesystem;

namespace {

// The environment a `retarget train` child runs with, read while it waits for a second rank.
std::string environment_of_training(const fs::path& dir, const std::vector<std::string>& env) {
  std::ofstream(dir / "sleepy.yaml") << "task: vae\ndata: {dataset: " << (dir / "missing").string() << "}\n";
  // A training that waits for its second rank: alive for RETARGET_DIST_TIMEOUT seconds.
  std::vector<std::string> all = env;
  all.insert(all.end(), {"WORLD_SIZE=2", "RANK=0", "MASTER_ADDR=127.0.0.1",
                         "MASTER_PORT=" + std::to_string(free_loopback_port()), "RETARGET_DIST_TIMEOUT=20"});
  const pid_t child = spawn_retarget({"train", (dir / "sleepy.yaml").string(), "--out", (dir / "run").string()}, all,
                                     dir / "child.log");
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // past the restart
  std::string environ_text = file_bytes(fs::path("/proc") / std::to_string(child) / "environ");
  ::kill(child, SIGKILL);
  wait_for(child);
  for (char& c : environ_text)
    if (c == '\0') c = '\n';
  return environ_text;
}

}  // namespace

TEST_CASE("retarget runs with OpenMP's passive wait unless a policy is set", "[train][threads]") {
  const fs::path dir = scratch_dir("passive_wait");
  ::unsetenv("OMP_WAIT_POLICY");
  CHECK_THAT(environment_of_training(dir, {}), Catch::Contains("OMP_WAIT_POLICY=PASSIVE\n"));
  CHECK_THAT(environment_of_training(dir, {"OMP_WAIT_POLICY=ACTIVE"}), Catch::Contains("OMP_WAIT_POLICY=ACTIVE\n"));
}
