// Tests for geometry/expression_blends.h: random blends of a face model's shapes.
#include "geometry/expression_blends.h"

#include <fmt/format.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <set>

#include "core/error.h"

using namespace retarget;

TEST_CASE("random blends: 1-4 distinct shapes in range, seeded, named in order", "[blends]") {
  const std::vector<std::string> shapes = {"jawOpen",      "eyeBlink_L",   "eyeBlink_R",
                                           "mouthSmile_L", "mouthSmile_R", "browInnerUp"};
  BlendOptions o;
  o.count = 200;
  o.seed = 7;
  const std::vector<ExpressionRecipe> blends = random_blends(shapes, o);
  REQUIRE(blends.size() == 200);
  std::set<size_t> sizes;
  for (size_t i = 0; i < blends.size(); ++i) {
    const ExpressionRecipe& b = blends[i];
    CHECK(b.name == fmt::format("blend{:03d}", i));
    REQUIRE(b.weights.size() >= 1);
    REQUIRE(b.weights.size() <= 4);
    sizes.insert(b.weights.size());
    for (const auto& [name, w] : b.weights) {
      CHECK(std::find(shapes.begin(), shapes.end(), name) != shapes.end());
      CHECK(w > 0.3);
      CHECK(w <= 1.0);
    }
  }
  CHECK(sizes == std::set<size_t>{1, 2, 3, 4});  // every size occurs in 200 draws
  // The same seed gives the same blends, another seed others.
  const std::vector<ExpressionRecipe> again = random_blends(shapes, o);
  for (size_t i = 0; i < blends.size(); ++i) CHECK(again[i].weights == blends[i].weights);
  o.seed = 8;
  CHECK(random_blends(shapes, o)[0].weights != blends[0].weights);
}

TEST_CASE("random blends avoid the references and clamp the shape count", "[blends]") {
  // With one shape and weights in [0.96, 1], every blend looks like the reference {a: 1}...
  BlendOptions o;
  o.count = 3;
  o.min_weight = 0.96;
  o.max_weight = 1.0;
  const std::vector<ExpressionRecipe> references = {{"A", {{"a", 1.0}}}};
  // ...unless a second shape exists: then only blends that use b (or a far from 1) come out.
  const std::vector<ExpressionRecipe> blends = random_blends({"a", "b"}, o, references);
  for (const ExpressionRecipe& b : blends) CHECK(b.weights.count("b") == 1);
  o.max_shapes = 9;  // clamped to the two shapes there are
  for (const ExpressionRecipe& b : random_blends({"a", "b"}, o)) CHECK(b.weights.size() <= 2);
}

TEST_CASE("random blends refuse bad options by name", "[blends]") {
  BlendOptions o;
  o.count = 1;
  o.min_weight = 0;
  CHECK_THROWS_WITH(random_blends({"a"}, o), Catch::Contains("blends.min_weight"));
  o = BlendOptions{};
  o.count = 1;
  o.max_shapes = 0;
  CHECK_THROWS_WITH(random_blends({"a"}, o), Catch::Contains("blends.max_shapes"));
  o = BlendOptions{};
  o.count = 2;
  CHECK_THROWS_WITH(random_blends({}, o), Catch::Contains("no expression shapes"));
  o.count = -1;
  CHECK_THROWS_WITH(random_blends({"a"}, o), Catch::Contains("blends.count"));
  o.count = 2000000000;  // refused at once, not generated
  CHECK_THROWS_WITH(random_blends({"a"}, o), "blends.count: expected 0 to 100000 blends (--blends), got 2000000000");
}
