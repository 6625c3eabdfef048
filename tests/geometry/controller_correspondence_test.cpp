#include "geometry/controller_correspondence.h"

#include <catch2/catch.hpp>
#include <fstream>

#include "test_support.h"

using namespace retarget;
using Catch::Contains;

TEST_CASE("correspondence tables load, including rows without a human counterpart", "[correspondence]") {
  const auto dir = test::scratch_dir("correspondence_ok");
  const auto table =
      load_controller_correspondence(test::write_file(dir, "c.yaml",
                                                      "avatar: lapin\n"
                                                      "controllers:\n"
                                                      "  smileLeft: {mouthSmile_L: 1.0}\n"
                                                      "  browUpLeft: {browInnerUp_L: 1, browOuterUp_L: 0.5}\n"
                                                      "  earWiggle: {}\n"
                                                      "  tongueOut:\n"));
  REQUIRE(table.size() == 4);
  CHECK(table.at("smileLeft").at("mouthSmile_L") == 1.0);
  CHECK(table.at("browUpLeft").at("browOuterUp_L") == 0.5);
  CHECK(table.at("earWiggle").empty());
  CHECK(table.at("tongueOut").empty());

  // What we write reads back unchanged.
  const std::string path = (dir / "out" / "correspondence.yaml").string();
  write_controller_correspondence(path, table, "lapin", "a header\nof two lines");
  CHECK(load_controller_correspondence(path) == table);
}

TEST_CASE("bad correspondence tables name the file, the line and the key", "[correspondence]") {
  const auto dir = test::scratch_dir("correspondence_errors");
  CHECK_THROWS_WITH(load_controller_correspondence((dir / "missing.yaml").string()), Contains("missing.yaml"));
  CHECK_THROWS_WITH(load_controller_correspondence(test::write_file(dir, "a.yaml", "avatar: x\n")),
                    Contains("a.yaml") && Contains("controllers") && Contains("missing"));
  CHECK_THROWS_WITH(load_controller_correspondence(test::write_file(dir, "b.yaml", "controllers: [smileLeft]\n")),
                    Contains("b.yaml") && Contains("controllers") && Contains("expected a map"));
  CHECK_THROWS_WITH(
      load_controller_correspondence(test::write_file(dir, "c.yaml", "controllers:\n  smileLeft: mouthSmile_L\n")),
      Contains("c.yaml:2") && Contains("controllers.smileLeft") && Contains("expected a map"));
  CHECK_THROWS_WITH(load_controller_correspondence(
                        test::write_file(dir, "d.yaml", "controllers:\n  smileLeft: {mouthSmile_L: lots}\n")),
                    Contains("d.yaml:2") && Contains("controllers.smileLeft.mouthSmile_L") && Contains("lots"));
  CHECK_THROWS_WITH(load_controller_correspondence(
                        test::write_file(dir, "e.yaml", "controllers:\n  smileLeft: {mouthSmile_L: .nan}\n")),
                    Contains("finite"));
  CHECK_THROWS_WITH(load_controller_correspondence(test::write_file(dir, "f.yaml", "controlers: {}\n")),
                    Contains("controlers") && Contains("controllers"));
}

TEST_CASE("a table is checked against the rig's controllers and the face model's blendshapes", "[correspondence]") {
  const ControllerCorrespondence table = {{"smileLeft", {{"mouthSmile_L", 1.0}}}, {"earWiggle", {}}};
  CHECK_NOTHROW(check_controller_correspondence(table, {"smileLeft", "earWiggle"}, {"mouthSmile_L"}, "c.yaml"));
  CHECK_THROWS_WITH(check_controller_correspondence(table, {"earWiggle"}, {"mouthSmile_L"}, "c.yaml"),
                    Contains("c.yaml") && Contains("controllers.smileLeft") && Contains("no controller"));
  CHECK_THROWS_WITH(check_controller_correspondence(table, {"smileLeft", "earWiggle"}, {"jawOpen"}, "c.yaml"),
                    Contains("controllers.smileLeft.mouthSmile_L") && Contains("no blendshape"));
  CHECK_THROWS_WITH(
      check_controller_correspondence(table, {"smileLeft", "earWiggle", "blinkLeft"}, {"mouthSmile_L"}, "c.yaml"),
      Contains("blinkLeft") && Contains("no row"));
}

TEST_CASE("human weights map to controller weights through the table", "[correspondence]") {
  const ControllerCorrespondence table = {{"smileLeft", {{"mouthSmile_L", 1.0}}},
                                          {"browUpLeft", {{"browInnerUp_L", 1.0}, {"browOuterUp_L", 1.0}}},
                                          {"halfJaw", {{"jawOpen", 0.5}}},
                                          {"earWiggle", {}}};
  auto y = controller_weights_from_human(
      table,
      {{"mouthSmile_L", 0.7}, {"browInnerUp_L", 1.0}, {"browOuterUp_L", 1.0}, {"jawOpen", 0.25}, {"cheekPuff_L", 1.0}});
  CHECK(y.at("smileLeft") == Approx(0.7));
  CHECK(y.at("browUpLeft") == Approx(1.0));
  CHECK(y.at("halfJaw") == Approx(0.5));
  CHECK(y.at("earWiggle") == 0.0);
  y = controller_weights_from_human(table, {{"browOuterUp_L", 1.0}, {"mouthSmile_L", -1.0}});
  CHECK(y.at("browUpLeft") == Approx(0.5));
  CHECK(y.at("smileLeft") == 0.0);  // clamped to [0, 1]
  y = controller_weights_from_human(table, {{"mouthSmile_L", -1.0}}, -1.0, 1.0);
  CHECK(y.at("smileLeft") == Approx(-1.0));
}
