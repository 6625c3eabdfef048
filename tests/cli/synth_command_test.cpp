#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "core/error.h"
#include "geometry/face_model.h"
#include "geometry/rig.h"
#include "run_command.h"
#include "test_support.h"

using namespace retarget;
using Catch::Contains;
namespace fs = std::filesystem;

namespace {

int run_synth(std::vector<std::string> args, std::string* printed = nullptr) {
  return test::run_command(cli::synth_command, "synth", std::move(args), printed);
}

}  // namespace

TEST_CASE("retarget synth writes the human, the avatars and a README", "[synth]") {
  const auto dir = test::scratch_dir("synth_command");
  const fs::path out = dir / "set";
  std::string printed;
  REQUIRE(run_synth({"--out", out.string(), "--seed", "5"}, &printed) == 0);
  CHECK_THAT(printed, Contains("human") && Contains("vertices") && Contains("controllers") && Contains("moppet"));
  CHECK(fs::exists(out / "README.txt"));
  const FaceModel human = load_face_model((out / "human").string());
  CHECK(human.expression_index("jawOpen") >= 0);
  for (const char* avatar : {"moppet", "fox", "glorp"}) {
    CHECK(fs::exists(out / "avatars" / avatar / "correspondence.yaml"));
    CHECK(load_rig_folder((out / "avatars" / avatar).string()).controller_count() >= 12);
  }

  // A folder with files in it is left alone unless --force.
  CHECK_THROWS_WITH(run_synth({"--out", out.string()}),
                    Contains(out.string()) && Contains("not empty") && Contains("--force"));
  CHECK(run_synth({"--out", out.string(), "--force"}) == 0);
  // An empty folder is fine.
  fs::create_directories(dir / "empty");
  CHECK(run_synth({"--out", (dir / "empty").string()}) == 0);
}

TEST_CASE("retarget synth explains bad arguments", "[synth]") {
  const auto dir = test::scratch_dir("synth_command_errors");
  CHECK_THROWS_WITH(run_synth({}), Contains("--out"));
  std::ofstream(dir / "file.txt") << "x";
  CHECK_THROWS_WITH(run_synth({"--out", (dir / "file.txt").string()}), Contains("not a folder"));
  CHECK(run_synth({"--help"}) == 0);
}
