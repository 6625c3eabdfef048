// `retarget avatar init` as a new user runs it: on a GLB an artist's tool wrote (here the
// synthetic fox, written as glTF in metres), then `retarget dataset` on the folder it writes.
#include <catch2/catch.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "geometry/face_model.h"
#include "geometry/rig.h"
#include "infer/gltf_animation.h"
#include "run_command.h"
#include "synthetic/synthetic_faces.h"
#include "test_support.h"

namespace retarget {
namespace avatar_command_test {

namespace fs = std::filesystem;
using Catch::Contains;

int run_avatar(std::vector<std::string> args, std::string* printed = nullptr) {
  return test::run_command(cli::avatar_command, "avatar", std::move(args), printed);
}

TEST_CASE("avatar init on a GLB writes a rig folder with the landmarks a person would place, and it builds a dataset",
          "[avatar][cli]") {
  const Rig fox = synthetic_avatars()[1].rig;
  REQUIRE(fox.name == "fox");
  const fs::path dir = test::scratch_dir("avatar_command_glb");
  const fs::path glb = dir / "fox.glb";
  write_gltf_animation(gltf_animation_input(fox, {Eigen::VectorXd::Zero(fox.controller_count())}), {}, glb.string());

  std::string printed;
  REQUIRE(run_avatar({"init", glb.string(), "--out", (dir / "fox").string()}, &printed) == 0);
  CHECK_THAT(printed, Contains("mouth_left") && Contains("landmarks.png"));
  CHECK(fs::exists(dir / "fox" / "landmarks.png"));
  CHECK(fs::exists(dir / "fox" / "proposals.yaml"));

  const Rig loaded = load_rig((dir / "fox").string());
  REQUIRE(loaded.neutral.vertex_count() == fox.neutral.vertex_count());
  CHECK(loaded.units == "m");
  for (const char* name : {"mouth_left", "mouth_right", "lip_upper_center", "lip_lower_center", "eye_inner_left",
                           "eye_outer_left", "eye_inner_right", "eye_outer_right"}) {
    INFO(name);
    REQUIRE(loaded.landmarks.count(name) == 1);
    // The GLB keeps the vertex order: the very vertices the generator marked.
    CHECK(loaded.landmarks.at(name) == fox.landmarks.at(name));
  }

  // The folder is a rig like any other: the pipeline's first step takes it as it is.
  std::vector<std::string> args = {"dataset",   "--rig", (dir / "fox").string(), "--out",  (dir / "dataset").string(),
                                   "--samples", "40",    "--no-preview",         "--force"};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  std::ostringstream quiet;
  std::streambuf* old = std::cout.rdbuf(quiet.rdbuf());
  const int code = cli::dataset_command(static_cast<int>(argv.size()), argv.data());
  std::cout.rdbuf(old);
  CHECK(code == 0);
  CHECK(fs::exists(dir / "dataset" / "manifest.yaml"));

  // A folder that is not empty is not overwritten without --force.
  CHECK_THROWS_WITH(run_avatar({"init", glb.string(), "--out", (dir / "fox").string()}), Contains("--force"));
}

TEST_CASE("avatar init and dataset refuse a mesh over the size limits before any work, naming the option",
          "[avatar][cli]") {
  const Rig fox = synthetic_avatars()[1].rig;
  const fs::path dir = test::scratch_dir("avatar_command_size");
  const fs::path glb = dir / "fox.glb";
  write_gltf_animation(gltf_animation_input(fox, {Eigen::VectorXd::Zero(fox.controller_count())}), {}, glb.string());
  const int vertices = fox.neutral.vertex_count();
  REQUIRE(vertices > 100);
  CHECK(test::error_of([&] {
          run_avatar({"init", glb.string(), "--out", (dir / "a").string(), "--max-vertices", "100"});
        }) == glb.string() + ": " + std::to_string(vertices) +
                  " vertices, more than the limit of 100 (it keeps memory and time in bounds); decimate the mesh, "
                  "or raise the limit with --max-vertices " +
                  std::to_string(vertices));
  CHECK(test::error_of([&] {
          run_avatar({"init", glb.string(), "--out", (dir / "b").string(), "--max-faces", "0"});
        }) == "--max-faces: expected a count >= 1, got 0");
  std::vector<std::string> args = {"dataset",     "--rig", glb.string(), "--out", (dir / "dataset").string(),
                                   "--max-faces", "10"};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  CHECK_THAT(test::error_of([&] { cli::dataset_command(static_cast<int>(argv.size()), argv.data()); }),
             Contains(glb.string() + ": ") && Contains("faces, more than the limit of 10 ") && Contains("--max-faces"));
  CHECK_FALSE(fs::exists(dir / "dataset" / "manifest.yaml"));
}

TEST_CASE("avatar landmarks: a bad option is named as the user typed it", "[avatar][cli]") {
  const Rig fox = synthetic_avatars()[1].rig;
  const fs::path dir = test::scratch_dir("avatar_command_landmarks_options");
  write_rig_folder((dir / "fox").string(), fox);
  write_face_model((dir / "human").string(), synthetic_human());
  const std::string model = (dir / "human" / "face_model.yaml").string();
  CHECK(test::error_of([&] {
          run_avatar({"landmarks", (dir / "fox").string(), "--face-model", model, "--port", "99999"});
        }) == "--port: must be in 0..65535, got 99999");
  CHECK_THAT(test::error_of([&] {
               run_avatar({"landmarks", (dir / "fox").string(), "--face-model", model, "--size", "5"});
             }),
             Catch::StartsWith("--size: "));
}

}  // namespace avatar_command_test
}  // namespace retarget
