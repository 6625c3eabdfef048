// `retarget pipeline` end to end on a tiny synthetic recipe, as a user runs it: killed with
// SIGKILL during its rounds of comparisons, run again it keeps the rounds that finished and
// resumes at the one the kill interrupted; a third run finds everything up to date.
#include <signal.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "child_process.h"
#include "pipeline/stage_manifest.h"
#include "scratch.h"

using namespace retarget;
using namespace retarget::test;
namespace fs = std::filesystem;

namespace {

// The demo recipe made tiny: few people and rig samples, one epoch per VAE, a few of F's, three
// rounds of 47 comparisons.
std::string tiny_recipe(const fs::path& dir) {
  const std::string demo = (fs::path(RETARGET_SOURCE_DIR) / "configs/recipes/demo.yaml").string();
  return write_file(dir, "tiny.yaml",
                    "base: " + demo +
                        "\n"
                        "human: {people: 6}\n"
                        "avatar: {samples: 150}\n"
                        "training:\n"
                        "  avatar_vae: [training.epochs=1, training.threads=1]\n"
                        "  human_vae: [training.epochs=1, training.threads=1]\n"
                        "  translation: ['stages=[{name: paired, epochs: 3, lr: 1.0e-3, weights: {paired: 1, group: "
                        "1.0e-4, triplet: 1.0e-4}}, {name: triplet, epochs: 3, lr: 1.0e-4, weights: {paired: 1, "
                        "group: 1, triplet: 10}}]', training.threads=1]\n"
                        "  cyclegan: [training.epochs=2, light_field.samples=12, similarity.epochs=2, "
                        "training.threads=1]\n"
                        "test_faces: {blends: 2}\n"
                        "method: {budget: 141, annotation_blends: 0}\n"
                        "extras: {pictures: false, geometry_demo: false}\n");
}

}  // namespace

TEST_CASE("a pipeline killed during its rounds resumes at the round the kill interrupted", "[pipeline][slow]") {
  const fs::path dir = scratch_dir("pipeline_kill");
  const std::string recipe = tiny_recipe(dir);
  const fs::path run = dir / "run";
  const std::vector<std::string> args = {"pipeline", recipe, "--out", run.string()};
  const pid_t first = spawn_retarget(args, dir / "first.log");
  REQUIRE(first > 0);
  // SIGKILL as soon as round 2 is under way (its manifest says running).
  const std::string round2 = stage_manifest_path(run.string(), "method/round-02");
  bool killed = false;
  for (int i = 0; i < 900000 && !killed; ++i) {  // up to 15 minutes on a loaded machine
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    std::error_code ec;
    if (fs::exists(round2, ec)) {
      try {
        const std::optional<StageManifest> m = load_stage_manifest(round2);
        if (m && !m->done()) {
          ::kill(first, SIGKILL);
          killed = true;
        }
      } catch (const Error&) {  // read while being replaced: try again
      }
    }
    int status = 0;
    if (!killed && ::waitpid(first, &status, WNOHANG) == first) break;  // ended on its own: fails below
  }
  INFO(file_bytes(dir / "first.log"));
  REQUIRE(killed);
  ::waitpid(first, nullptr, 0);
  REQUIRE(load_stage_manifest(stage_manifest_path(run.string(), "method/round-01"))->done());
  const std::string round1_answers = file_bytes(run / "method/rounds/1/annotation/annotations.db");
  CHECK(!fs::exists(run / "method/evaluation/metrics.json"));

  const pid_t second = spawn_retarget(args, dir / "second.log");
  const int status = wait_for(second);
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  const std::string log = file_bytes(dir / "second.log");
  INFO(log);
  REQUIRE(code == 0);
  CHECK_THAT(log, Catch::Contains("runs/human_vae: up to date"));
  CHECK_THAT(log, Catch::Contains("method/round-01: up to date"));
  CHECK_THAT(log, Catch::Contains("] method/round-02: round 2 of 3"));
  CHECK_THAT(log, Catch::Contains("] method/round-03: round 3 of 3"));
  CHECK(file_bytes(run / "method/rounds/1/annotation/annotations.db") == round1_answers);  // not asked again
  CHECK(fs::exists(run / "method/evaluation/metrics.json"));
  CHECK_THAT(file_bytes(run / "method/evaluation/comparison.csv"), Catch::Contains("references,cyclegan,"));
  CHECK(fs::exists(run / "runs/cyclegan/plots/training.png"));
  CHECK(fs::exists(run / "method/evaluation/ladder/ladder.json"));
  CHECK_THAT(file_bytes(run / "summary.txt"), Catch::Contains("references (47 faces)"));
  CHECK(load_stage_manifest(stage_manifest_path(run.string(), "method/plots"))->done());
  CHECK(fs::file_size(run / "method/evaluation/plots/methods.png") > 1000);

  const pid_t third = spawn_retarget(args, dir / "third.log");
  REQUIRE(WEXITSTATUS(wait_for(third)) == 0);
  CHECK_THAT(file_bytes(dir / "third.log"), Catch::Contains("19 stages, 19 up to date, 0 to run"));
}
