#include "train/run_folder.h"

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "test_support.h"

using namespace retarget;
using namespace retarget::test;
namespace fs = std::filesystem;

namespace {

void write(const fs::path& path, const std::string& text) { std::ofstream(path.string()) << text; }

const char* const kOldRunYaml =
    "status: finished\n"
    "task: vae\n"
    "epochs_done: 3\n"
    "epochs_planned: 3\n"
    "best_epoch: 2\n"
    "best_validation: 0.0123\n"
    "fingerprints:\n"
    "  dataset: abc\n"
    "software_version: 0.1.0\n"
    "started: 2024-01-01T00:00:00Z\n"
    "updated: 2024-01-01T00:01:00Z\n"
    "finished: 2024-01-01T00:01:00Z\n";

}  // namespace

TEST_CASE("run.yaml written before baselines and warnings still loads", "[run_folder]") {
  const fs::path dir = scratch_dir("run_folder_old_yaml");
  write(dir / "run.yaml", kOldRunYaml);
  const RunStatus s = RunStatus::load(dir.string());
  CHECK(s.status == "finished");
  CHECK(s.best_epoch == 2);
  CHECK(s.fingerprints.at("dataset") == "abc");
  CHECK(s.baselines.empty());
  CHECK(s.warnings.empty());
}

TEST_CASE("run.yaml keeps the baselines and warnings", "[run_folder]") {
  const fs::path dir = scratch_dir("run_folder_baselines");
  RunStatus s;
  s.task = "vae";
  s.baselines = {{"neutral", 0.0454}, {"mean", 0.0431}};
  s.warnings = {"does not beat the trivial answer: validation L1 0.04450 vs mean 0.04310 (x1.03)",
                "stopped improving after epoch 2 of 30"};
  s.save(dir.string());
  const RunStatus back = RunStatus::load(dir.string());
  CHECK(back.baselines == s.baselines);
  CHECK(back.warnings == s.warnings);

  write(dir / "run.yaml", std::string(kOldRunYaml) + "baselines: {neutral: low}\n");
  CHECK_THROWS_WITH(RunStatus::load(dir.string()),
                    Catch::Contains("run.yaml") && Catch::Contains("baselines.neutral") && Catch::Contains("low"));
  write(dir / "run.yaml", std::string(kOldRunYaml) + "warnings: {a: 1}\n");
  CHECK_THROWS_WITH(RunStatus::load(dir.string()), Catch::Contains("run.yaml") && Catch::Contains("warnings"));
}

TEST_CASE("a metrics row with new columns keeps one CSV header (a run resumed by a newer version)", "[run_folder]") {
  const fs::path dir = scratch_dir("run_folder_columns") / "run";
  RunFolder run(dir.string(), "vae", "task: vae\n", RunStart::fresh);
  run.append_metrics({{"epoch", 1}, {"validation_l1", 0.5}});
  run.append_metrics({{"epoch", 2}, {"validation_l1", 0.4}, {"neutral_validation_l1", 0.6}});
  std::ifstream csv((dir / "metrics.csv").string());
  std::vector<std::string> lines;
  for (std::string line; std::getline(csv, line);) lines.push_back(line);
  REQUIRE(lines.size() == 3);
  CHECK(lines[0] == "epoch,validation_l1,neutral_validation_l1");
  CHECK(lines[1] == "1,0.5,nan");
  CHECK(lines[2] == "2,0.4,0.6");
  const auto rows = read_metrics(dir.string());
  REQUIRE(rows.size() == 2);
  CHECK(rows[1].at("neutral_validation_l1") == 0.6);
}
