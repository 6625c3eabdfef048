#include "geometry/landmarks.h"

#include <catch2/catch.hpp>
#include <fstream>

#include "test_support.h"

using namespace retarget;

TEST_CASE("landmark pairs load from every supported form", "[landmarks]") {
  const auto dir = test::scratch_dir("landmarks_forms");
  const auto pairs = read_landmark_pairs(test::write_file(dir, "pairs.yaml", "pairs: [[0, 5], [3, 7]]\n"));
  REQUIRE(pairs.size() == 2);
  CHECK((pairs[1].source == 3 && pairs[1].target == 7));
  const auto lists = read_landmark_pairs(test::write_file(dir, "lists.yaml", "source: [1, 2, 3]\ntarget: [4, 5, 6]\n"));
  REQUIRE(lists.size() == 3);
  CHECK((lists[2].source == 3 && lists[2].target == 6));
  const auto same = read_landmark_pairs(test::write_file(dir, "same.yaml", "same: [9, 8]\n"));
  CHECK((same[0].source == 9 && same[0].target == 9));
  // JSON with a named list, like the ICT model's vertex_indices.json.
  const auto keyed =
      read_landmark_pairs(test::write_file(dir, "model.json", "{\"other\": [1], \"idx\": [10, 11, 12]}"), "idx");
  CHECK(keyed.size() == 3);
  CHECK(keyed[2].target == 12);
  const EyeLandmarks eyes =
      read_eye_landmarks(test::write_file(dir, "eyes.yaml", "left_eye: [1, 2]\nright_eye: [3]\n"));
  CHECK(eyes.left == std::vector<int>{1, 2});
  CHECK(eyes.right == std::vector<int>{3});
}

TEST_CASE("bad landmark files name the file, the key and the entry", "[landmarks]") {
  const auto dir = test::scratch_dir("landmarks_errors");
  CHECK_THROWS_WITH(
      read_landmark_pairs(test::write_file(dir, "a.yaml", "pairs: [[0, 5], [3]]\n")),
      Catch::Contains("a.yaml") && Catch::Contains("pairs[1]") && Catch::Contains("expected [source, target]"));
  CHECK_THROWS_WITH(read_landmark_pairs(test::write_file(dir, "b.yaml", "source: [1, 2]\ntarget: [4]\n")),
                    Catch::Contains("target") && Catch::Contains("has 1 indices but source has 2"));
  CHECK_THROWS_WITH(read_landmark_pairs(test::write_file(dir, "c.yaml", "same: [1, -4]\n")),
                    Catch::Contains("same[1]") && Catch::Contains("-4"));
  CHECK_THROWS_WITH(read_landmark_pairs(test::write_file(dir, "d.yaml", "source: [1]\ntarget: [2]\nsorce: [3]\n")),
                    Catch::Contains("sorce"));
  CHECK_THROWS_WITH(read_landmark_pairs((dir / "missing.yaml").string()), Catch::Contains("missing.yaml"));
  CHECK_THROWS_WITH(read_eye_landmarks(test::write_file(dir, "e.yaml", "left_eye: [1]\n")),
                    Catch::Contains("right_eye"));
}

TEST_CASE("landmark indices are checked against both meshes", "[landmarks]") {
  const std::vector<LandmarkPair> pairs = {{0, 0}, {5, 12000}};
  CHECK_THROWS_WITH(check_landmark_pairs(pairs, 100, "human.obj", 11248, "avatar.obj"),
                    Catch::Contains("landmark 1") && Catch::Contains("target vertex 12000") &&
                        Catch::Contains("avatar.obj has 11248 vertices"));
  CHECK_NOTHROW(check_landmark_pairs(pairs, 100, "human.obj", 12001, "avatar.obj"));
}
