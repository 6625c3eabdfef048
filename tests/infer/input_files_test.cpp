#include "infer/input_files.h"

// LibTorch before Catch: glog (through c10) defines CHECK, and the last definition wins.
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/infer/infer_test_support.h"

namespace retarget {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> names(const std::vector<InputFile>& files) {
  std::vector<std::string> out;
  for (const InputFile& f : files) out.push_back(f.problem.empty() ? fs::path(f.path).filename().string() : "!");
  return out;
}

TEST_CASE("natural_less orders digit runs by value", "[input_files]") {
  const auto [a, b, less] = GENERATE(table<std::string, std::string, bool>({
      {"frame_2.obj", "frame_10.obj", true},
      {"frame_10.obj", "frame_2.obj", false},
      {"frame_9.obj", "frame_9.obj", false},
      {"a9b", "a10a", true},
      {"x7", "x007", true},  // equal values: fewer leading zeros first
      {"x007", "x7", false},
      {"x007", "x8", true},
      {"take2_frame_100", "take10_frame_1", true},
      {"b", "a10", false},
      {"frame", "frame_1", true},
      {"frame_0001", "frame_0002", true},
  }));
  INFO(a << " < " << b);
  CHECK(natural_less(a, b) == less);
}

TEST_CASE("expand_inputs: folders and globs in natural order, files as given", "[input_files]") {
  const fs::path dir = test::scratch_dir("infer_input_files");
  test::write_frames(dir / "seq", {10, 2, 1, 9});
  test::write_text(dir / "seq" / "notes.txt", "not a mesh\n");
  test::write_text(dir / "seq" / "extra.PLY", "");  // a mesh by its name; reading it will fail
  fs::create_directories(dir / "seq" / "sub.obj");  // a folder is skipped, whatever its name
  fs::create_directories(dir / "empty");

  CHECK(names(expand_inputs({(dir / "seq").string()})) ==
        std::vector<std::string>({"extra.PLY", "frame_1.obj", "frame_2.obj", "frame_9.obj", "frame_10.obj"}));
  CHECK(names(expand_inputs({(dir / "seq" / "frame_*.obj").string()})) ==
        std::vector<std::string>({"frame_1.obj", "frame_2.obj", "frame_9.obj", "frame_10.obj"}));
  CHECK(names(expand_inputs({(dir / "seq" / "frame_?.obj").string()})) ==
        std::vector<std::string>({"frame_1.obj", "frame_2.obj", "frame_9.obj"}));
  // Inputs keep their own order; files pass through as named, missing ones with a problem ("!").
  CHECK(names(expand_inputs({(dir / "seq" / "frame_10.obj").string(), (dir / "seq" / "frame_1*.obj").string(),
                             (dir / "missing.obj").string()})) ==
        std::vector<std::string>({"frame_10.obj", "frame_1.obj", "frame_10.obj", "!"}));
  // A path that does not exist, file or (mistyped) folder, says so instead of being read.
  for (const fs::path& absent : {dir / "missing.obj", dir / "no_such_folder", dir / "seq" / "nope" / "frames"}) {
    const std::vector<InputFile> files = expand_inputs({absent.string()});
    REQUIRE(files.size() == 1);
    CHECK(files[0].path == absent.string());
    CHECK(files[0].problem == "no such file or folder: the path does not exist");
  }

  const std::vector<InputFile> empty = expand_inputs({(dir / "empty").string()});
  REQUIRE(empty.size() == 1);
  CHECK(empty[0].path == (dir / "empty").string());
  CHECK_THAT(empty[0].problem, Catch::Contains("no .obj, .ply or .off files"));
  const std::vector<InputFile> nothing = expand_inputs({(dir / "seq" / "take_*.obj").string()});
  REQUIRE(nothing.size() == 1);
  CHECK_THAT(nothing[0].problem, Catch::Contains("matches no .obj, .ply or .off file"));
}

TEST_CASE("is_mesh_file knows the readable extensions", "[input_files]") {
  CHECK(is_mesh_file("a.obj"));
  CHECK(is_mesh_file("dir/a.OFF"));
  CHECK(is_mesh_file("a.Ply"));
  CHECK_FALSE(is_mesh_file("a.stl"));
  CHECK_FALSE(is_mesh_file("obj"));
}

}  // namespace
}  // namespace retarget
