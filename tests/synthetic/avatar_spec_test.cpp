#include "synthetic/avatar_spec.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <functional>
#include <string>

using namespace retarget;
using namespace retarget::synth;

namespace {

const AvatarSpec& spec(const std::string& name) {
  for (const AvatarSpec& s : avatar_specs())
    if (s.name == name) return s;
  FAIL("no avatar spec " << name);
  throw;
}

int controller_count(const AvatarSpec& s) {
  int n = 0;
  for (const ControllerSpec& c : s.controllers) n += c.sides == Sides::kPair ? 2 : 1;
  return n;
}

}  // namespace

TEST_CASE("avatar_specs: the bundled tables are valid, in synthetic_avatars() order") {
  const std::vector<AvatarSpec>& specs = avatar_specs();
  REQUIRE(specs.size() == 3);
  CHECK(specs[0].name == "moppet");
  CHECK(specs[1].name == "fox");
  CHECK(specs[2].name == "glorp");
  for (const AvatarSpec& s : specs) CHECK_NOTHROW(s.validate());
  // The counts synthetic_faces.h promises.
  CHECK(controller_count(specs[0]) == 21);
  CHECK(controller_count(specs[1]) == 22);
  CHECK(controller_count(specs[2]) == 17);
}

TEST_CASE("build_avatar: a changed table changes the avatar (parts and their controllers removed)") {
  AvatarSpec fox = spec("fox");
  const SyntheticAvatar with_ears = build_avatar(fox);
  fox.name = "earless";
  fox.parts = {};
  fox.controllers.erase(std::remove_if(fox.controllers.begin(), fox.controllers.end(),
                                       [](const ControllerSpec& c) { return c.name.rfind("ear", 0) == 0; }),
                        fox.controllers.end());
  const SyntheticAvatar earless = build_avatar(fox);
  CHECK(earless.rig.name == "earless");
  // Two ears of 7 rings x 14 segments plus a tip each.
  CHECK(earless.rig.neutral.vertex_count() == with_ears.rig.neutral.vertex_count() - 2 * (7 * 14 + 1));
  CHECK(earless.rig.controller_count() == with_ears.rig.controller_count() - 3);
  CHECK(earless.rig.controller_index("earsBack") < 0);
  CHECK(earless.correspondence.count("snarlRight") == 1);
  CHECK(earless.correspondence.at("snarlRight").count("noseSneer_R") == 1);
  // The skin is the same.
  const int skin = earless.rig.neutral.vertex_count();
  CHECK(earless.rig.neutral.vertices == with_ears.rig.neutral.vertices.topRows(skin));
  CHECK(earless.rig.landmarks == with_ears.rig.landmarks);
}

TEST_CASE("AvatarSpec::validate names what it cannot build") {
  struct Case {
    const char* what;
    std::function<void(AvatarSpec&)> change;
    const char* message;
  };
  const Case cases[] = {
      {"too few grid lines", [](AvatarSpec& s) { s.grid.x.count = 2; }, "fox.grid.x.count: expected at least 3"},
      {"a flat relief bump", [](AvatarSpec& s) { std::get<BumpRelief>(s.relief[1]).bump.ry = 0; },
       "fox.relief[1].bump: expected positive radii"},
      {"ear motions without ears", [](AvatarSpec& s) { s.parts = {}; },
       "fox.controllers[10].deformation: a part motion needs parts"},
      {"a repeated controller", [](AvatarSpec& s) { s.controllers.push_back(s.controllers[0]); },
       "controller \"blinkLeft\" appears twice"},
      {"a pair's human name without a side", [](AvatarSpec& s) { s.controllers[0].human = {"eyeBlink"}; },
       "fox.controllers[0].human: \"eyeBlink\": a pair's names end in _L or Left"},
      {"lids summed", [](AvatarSpec& s) { s.controllers[0].sides = Sides::kSummed; },
       "fox.controllers[0].sides: kSummed is for a Displacement only"},
  };
  for (const Case& c : cases) {
    INFO(c.what);
    AvatarSpec s = spec("fox");
    c.change(s);
    CHECK_THROWS_WITH(s.validate(), Catch::Contains(c.message));
    CHECK_THROWS_WITH(build_avatar(s), Catch::Contains(c.message));
  }
}
