// The folder `retarget avatar init` writes: a rig folder the pipeline loads as it is, with the
// proposals in it, proposals.yaml and landmarks.png.
#include "avatar/avatar_init.h"

#include <stb/stb_image.h>
#include <yaml-cpp/yaml.h>

#include <catch2/catch.hpp>
#include <filesystem>

#include "avatar/landmark_sheet.h"
#include "scratch.h"
#include "synthetic/synthetic_faces.h"

namespace retarget {
namespace avatar_init_test {

TEST_CASE("avatar init writes a rig folder that loads with the proposed landmarks and eyes", "[avatar][init]") {
  const Rig glorp = synthetic_avatars()[2].rig;
  REQUIRE(glorp.name == "glorp");
  const LandmarkProposal proposal = propose_landmarks(glorp);
  const std::filesystem::path folder = test::scratch_dir("avatar_init_glorp");
  write_avatar_folder(folder.string(), glorp, proposal);

  const Rig loaded = load_rig((folder / "rig.yaml").string());
  REQUIRE(loaded.controller_count() == glorp.controller_count());
  CHECK(loaded.neutral.vertices.isApprox(glorp.neutral.vertices, 1e-6));
  REQUIRE(loaded.landmarks.size() == proposal.landmarks.size());
  for (const auto& [name, landmark] : proposal.landmarks) CHECK(loaded.landmarks.at(name) == landmark.vertex);
  CHECK(loaded.eyes.left == proposal.eyes.left);
  CHECK(loaded.eyes.right == proposal.eyes.right);
  // The parts, as the rig names them: glorp's eyeballs, its teeth and the mouth's pocket.
  REQUIRE(loaded.parts.size() == proposal.parts.size());
  int eyes = 0, teeth = 0;
  for (const RigPart& part : loaded.parts) {
    eyes += part.kind == PartKind::eye_left || part.kind == PartKind::eye_right;
    teeth += part.kind == PartKind::teeth;
  }
  CHECK(eyes == 2);
  CHECK(teeth == 2);
  // Every proposal is listed with its confidence, and the hand-placed comparison finds them equal.
  const YAML::Node yaml = YAML::LoadFile((folder / "proposals.yaml").string());
  CHECK(yaml["landmarks"].size() == proposal.landmarks.size());
  CHECK(yaml["landmarks"]["mouth_left"]["confidence"].as<double>() > 0.5);
  CHECK(yaml["parts"].size() == proposal.parts.size());
  const std::map<std::string, double> distances = landmark_distances(glorp, proposal);
  CHECK(distances.at("mouth_left") < 1e-12);

  int width = 0, height = 0, channels = 0;
  unsigned char* pixels = stbi_load((folder / "landmarks.png").string().c_str(), &width, &height, &channels, 3);
  REQUIRE(pixels != nullptr);
  stbi_image_free(pixels);
  CHECK(width == 2 * LandmarkSheetOptions{}.view_size);
  CHECK(height > LandmarkSheetOptions{}.view_size);
}

}  // namespace avatar_init_test
}  // namespace retarget
