// Avatar datasets of glTF rigs (data/dataset.h): the meshes used are recorded and read back, and
// what later steps need (the eyes) is checked before any work.
// data/dataset.h first (kept there against the include sorting): it includes LibTorch, whose
// glog CHECK macro must come before Catch's, or the build without the precompiled header fails.
// clang-format off
#include "data/dataset.h"
// clang-format on

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/log.h"
#include "geometry/rig.h"
#include "gltf_avatar_file.h"
#include "test_support.h"

using namespace retarget;
using Catch::Contains;

namespace dataset_gltf_test {

namespace fs = std::filesystem;

AvatarDatasetOptions gltf_options() {
  AvatarDatasetOptions o;
  o.samples = 12;
  o.test_fraction = 0.25;
  o.progress = nullptr;
  return o;
}

std::string manifest_text(const fs::path& folder) {
  std::ifstream in(folder / "manifest.yaml");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace dataset_gltf_test

using namespace dataset_gltf_test;

TEST_CASE("an avatar dataset of a glTF file records the meshes it used and reloads them", "[dataset][gltf]") {
  const fs::path dir = test::scratch_dir("dataset_gltf_meshes");
  const std::string gltf = test::write_test_gltf_avatar(dir / "avatar.gltf");
  AvatarDatasetOptions options = gltf_options();
  options.mesh_name = "Face";  // not the default: Body has more morph targets
  build_avatar_dataset(gltf, (dir / "face").string(), options);
  CHECK_THAT(manifest_text(dir / "face"), Contains("gltf_meshes: [Face, EyeLeft, EyeRight]"));

  const Dataset d = load_dataset((dir / "face").string());
  CHECK(d.gltf_meshes == std::vector<std::string>{"Face", "EyeLeft", "EyeRight"});
  CHECK(d.vertex_count() == 36 + 2 * 9);
  CHECK(d.controllers == std::vector<std::string>{"ctrl0", "ctrl1", "ctrl2", "ctrl3"});
  CHECK(d.eyes.left.size() == 9);  // from the EyeLeft mesh: the eye check passed
  const Rig rig = load_dataset_rig(d);
  CHECK(rig.neutral.vertex_count() == d.vertex_count());
  CHECK(rig.gltf_meshes == d.gltf_meshes);
  // What reloading without the record would read: the Body, another avatar.
  CHECK(load_rig(d.source).gltf_meshes.front() == "Body");

  Dataset other = d;
  other.gltf_meshes = {"Body"};
  CHECK_THROWS_WITH(load_dataset_rig(other), Contains("avatar.gltf") && Contains("(glTF meshes Body)") &&
                                                 Contains("not the avatar dataset") && Contains("rebuild the dataset"));
  other.gltf_meshes = {"Nose"};
  CHECK_THROWS_WITH(load_dataset_rig(other), Contains("the avatar dataset's rig does not load (glTF meshes Nose)") &&
                                                 Contains("no mesh named \"Nose\""));
}

TEST_CASE("a rig.yaml pointing at a glTF file builds an avatar dataset with its landmarks", "[dataset][gltf]") {
  const fs::path dir = test::scratch_dir("dataset_gltf_yaml");
  test::write_test_gltf_avatar(dir / "avatar.gltf");
  std::ofstream(dir / "rig.yaml") << "gltf: avatar.gltf\nmesh: Face\nname: face\n"
                                     "landmarks: {nose_tip: 14, chin: 2, brow: 30}\n";
  build_avatar_dataset((dir / "rig.yaml").string(), (dir / "data").string(), gltf_options());
  const Dataset d = load_dataset((dir / "data").string());
  CHECK(d.name == "face");
  CHECK(d.units == "m");
  CHECK(d.landmarks.at("nose_tip") == 14);
  CHECK(d.eyes.right.front() == 45);  // EyeRight follows Face (36) and EyeLeft (9)
  CHECK(d.gltf_meshes == std::vector<std::string>{"Face", "EyeLeft", "EyeRight"});
  CHECK(load_dataset_rig(d).neutral.vertex_count() == 54);
}

TEST_CASE("an avatar dataset without eyes fails before any work, saying how to add them", "[dataset][gltf][errors]") {
  const fs::path dir = test::scratch_dir("dataset_gltf_no_eyes");
  const std::string gltf = test::write_test_gltf_avatar(dir / "plain.gltf", false);
  const fs::path out = dir / "data";
  CHECK_THROWS_WITH(build_avatar_dataset(gltf, out.string(), gltf_options()),
                    Contains("plain.gltf") && Contains("no eyes: `retarget eval retarget` measures errors in mm") &&
                        Contains("write a rig.yaml beside it with `gltf: plain.gltf`") &&
                        Contains("EyeLeft/EyeRight") && Contains("--allow-no-eyes"));
  CHECK(!fs::exists(out));  // refused before the folder was made

  std::ofstream(dir / "rig.yaml") << "gltf: plain.gltf\nmesh: Face\n";
  CHECK_THROWS_WITH(build_avatar_dataset((dir / "rig.yaml").string(), out.string(), gltf_options()),
                    Contains("rig.yaml: no eyes") && Contains("add them to ") && Contains("rig.yaml (`eyes:"));

  // Opted out: the dataset builds, with a warning that correspond will need --landmarks.
  std::vector<std::string> warnings;
  const log::Sink previous = log::set_sink([&](log::Level level, const std::string& m) {
    if (level == log::Level::warn) warnings.push_back(m);
  });
  AvatarDatasetOptions options = gltf_options();
  options.require_eyes = false;
  build_avatar_dataset(gltf, out.string(), options);
  log::set_sink(previous);
  CHECK(load_dataset(out.string()).eyes.left.empty());
  bool landmarks_warning = false;
  for (const std::string& w : warnings)
    landmarks_warning |= w.find("0 landmark(s); `retarget correspond` pairs at least 3") != std::string::npos;
  CHECK(landmarks_warning);
}
