#include "geometry/face_model.h"

#include <catch2/catch.hpp>
#include <fstream>

#include "core/error.h"
#include "geometry/mesh_io.h"
#include "test_support.h"

using namespace retarget;
namespace fs = std::filesystem;

namespace {

std::string write_text(const fs::path& dir, const std::string& name, const std::string& text) {
  const fs::path path = dir / name;
  fs::create_directories(path.parent_path());
  std::ofstream(path) << text;
  return path.string();
}

// A 4 x 4 vertex grid: the neutral of a tiny face model.
Mesh tiny_neutral() { return test::quad_grid(3, 3, 3.0, 3.0); }

// Positions of shape k: the neutral moved by a pattern that differs per k.
Positions shape_positions(const Mesh& neutral, int k) {
  Positions p = neutral.vertices;
  for (int v = 0; v < p.rows(); ++v) p(v, 2) += 0.1 * (k + 1) * std::sin(v + k);
  return p;
}

// Writes a face model folder: neutral.obj, identities/id{0,1}.obj, expressions/{jawOpen, smile_L,
// smile_R}.obj (absolute positions) and face_model.yaml with `extra` appended.
std::string write_tiny_model(const fs::path& dir, const std::string& extra = "") {
  const Mesh neutral = tiny_neutral();
  write_mesh((dir / "neutral.obj").string(), neutral);
  write_mesh((dir / "identities/id0.obj").string(), with_positions(neutral, shape_positions(neutral, 0)));
  write_mesh((dir / "identities/id1.obj").string(), with_positions(neutral, shape_positions(neutral, 1)));
  const char* names[] = {"jawOpen", "smile_L", "smile_R"};
  for (int k = 0; k < 3; ++k)
    write_mesh((dir / "expressions" / (std::string(names[k]) + ".obj")).string(),
               with_positions(neutral, shape_positions(neutral, 2 + k)));
  return write_text(dir, "face_model.yaml",
                    "name: tiny\n"
                    "units: mm\n"
                    "neutral: neutral.obj\n"
                    "shapes: absolute\n"
                    "identities:\n"
                    "  - {name: id0, file: identities/id0.obj}\n"
                    "  - {name: id1, file: identities/id1.obj}\n"
                    "expressions:\n"
                    "  - {name: jawOpen, file: expressions/jawOpen.obj}\n"
                    "  - {name: smile_L, file: expressions/smile_L.obj}\n"
                    "  - {name: smile_R, file: expressions/smile_R.obj}\n"
                    "landmarks: {nose_tip: 5, chin: 1}\n"
                    "eyes: {left: [10, 11], right: [8, 9]}\n" +
                        extra);
}

// The same model's YAML with one line replaced.
std::string variant(const fs::path& dir, const std::string& name, const std::string& from, const std::string& to) {
  std::ifstream in(dir / "face_model.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  text.replace(at, from.size(), to);
  return write_text(dir, name, text);
}

}  // namespace

TEST_CASE("a face model loads with paths relative to its file", "[face_model]") {
  const auto dir = test::scratch_dir("face_model_load");
  const std::string path = write_tiny_model(dir);
  const FaceModel model = load_face_model(path);
  const Mesh neutral = tiny_neutral();
  CHECK(model.name == "tiny");
  CHECK(model.units == "mm");
  CHECK(model.source == path);
  REQUIRE(model.identities.size() == 2);
  REQUIRE(model.expressions.size() == 3);
  CHECK(model.identities[1].name == "id1");
  CHECK(model.expressions[2].name == "smile_R");
  CHECK(model.identities[1].offset.isApprox(shape_positions(neutral, 1) - neutral.vertices));
  CHECK((model.expressions[0].offset - (shape_positions(neutral, 2) - neutral.vertices)).cwiseAbs().maxCoeff() < 1e-12);
  CHECK(model.landmarks.at("nose_tip") == 5);
  CHECK(model.eyes.left == std::vector<int>{10, 11});
  CHECK(model.expression_index("smile_L") == 1);
  CHECK(model.expression_index("frown") == -1);
  // The folder works as well as the file; the name defaults to the folder's.
  CHECK(load_face_model(dir.string()).identities.size() == 2);
  const FaceModel unnamed = load_face_model(variant(dir, "unnamed.yaml", "name: tiny\n", ""));
  CHECK(unnamed.name == "face_model_load");
}

TEST_CASE("a face model builds people and expressions linearly", "[face_model]") {
  const auto dir = test::scratch_dir("face_model_person");
  const FaceModel model = load_face_model(write_tiny_model(dir));
  Eigen::VectorXd c(2);
  c << 0.5, -1.5;
  const Positions person = model.person(c);
  const Positions expected =
      model.neutral.vertices + 0.5 * model.identities[0].offset - 1.5 * model.identities[1].offset;
  CHECK((person - expected).cwiseAbs().maxCoeff() < 1e-12);
  // Missing trailing coefficients are zero.
  Eigen::VectorXd one(1);
  one << 0.5;
  CHECK((model.person(one) - (model.neutral.vertices + 0.5 * model.identities[0].offset)).cwiseAbs().maxCoeff() <
        1e-12);
  const Positions smile = model.expression(person, {{"smile_L", 0.25}, {"jawOpen", 1.0}});
  CHECK((smile - (person + 0.25 * model.expressions[1].offset + model.expressions[0].offset)).cwiseAbs().maxCoeff() <
        1e-12);
  CHECK_THROWS_WITH(model.expression(person, {{"frown", 1.0}}),
                    Catch::Contains("unknown expression blendshape \"frown\"") && Catch::Contains("face_model.yaml"));
  CHECK_THROWS_WITH(model.person(Eigen::VectorXd::Ones(3)),
                    Catch::Contains("3 identity coefficients") && Catch::Contains("2 identity modes"));
}

TEST_CASE("a face model with offset shapes reads the files as offsets", "[face_model]") {
  const auto dir = test::scratch_dir("face_model_offsets");
  write_tiny_model(dir);
  const FaceModel absolute = load_face_model((dir / "face_model.yaml").string());
  const FaceModel offsets = load_face_model(variant(dir, "offsets.yaml", "shapes: absolute", "shapes: offsets"));
  CHECK((offsets.expressions[1].offset - (absolute.expressions[1].offset + absolute.neutral.vertices))
            .cwiseAbs()
            .maxCoeff() < 1e-12);
}

TEST_CASE("write_face_model round-trips a face model", "[face_model]") {
  const auto dir = test::scratch_dir("face_model_write");
  FaceModel model = load_face_model(write_tiny_model(dir / "in"));
  model.expressions[2].name = "smile/R";  // not a file name: written under a safe one
  write_face_model((dir / "out").string(), model);
  const FaceModel back = load_face_model((dir / "out").string());
  CHECK(back.name == "tiny");
  CHECK(back.units == "mm");
  REQUIRE(back.expressions.size() == 3);
  CHECK(back.expressions[2].name == "smile/R");
  CHECK(fs::exists(dir / "out/expressions/smile_R.obj"));
  for (size_t k = 0; k < 3; ++k)
    CHECK((back.expressions[k].offset - model.expressions[k].offset).cwiseAbs().maxCoeff() < 1e-12);
  CHECK((back.identities[1].offset - model.identities[1].offset).cwiseAbs().maxCoeff() < 1e-12);
  CHECK(back.landmarks == model.landmarks);
  CHECK(back.eyes.right == model.eyes.right);
}

TEST_CASE("bad face models name the file, the key path and the fault", "[face_model]") {
  const auto dir = test::scratch_dir("face_model_errors");
  write_tiny_model(dir);
  const Mesh small = test::quad_grid(2, 2, 1.0, 1.0);
  write_mesh((dir / "small.obj").string(), small);

  struct Case {
    const char* what;
    std::string from, to;
    std::vector<std::string> message;
  };
  const std::vector<Case> cases = {
      {"missing file",
       "expressions/smile_L.obj",
       "expressions/nope.obj",
       {"expressions[1].file", "mesh file not found", "nope.obj"}},
      {"missing neutral", "neutral: neutral.obj", "neutral: gone.obj", {"neutral", "gone.obj"}},
      {"vertex count",
       "expressions/smile_R.obj",
       "small.obj",
       {"expressions[2]", "small.obj has 9 vertices", "neutral", "neutral.obj has 16"}},
      {"duplicate name",
       "{name: smile_R,",
       "{name: smile_L,",
       {"expressions[2].name", "duplicate name \"smile_L\"", "also expressions[1]"}},
      {"unknown key", "units: mm", "unit: mm", {"unit", "unknown key", "units"}},
      {"unknown entry key", "{name: id0, file:", "{name: id0, path: x, file:", {"identities[0]", "path"}},
      {"landmark range",
       "nose_tip: 5",
       "nose_tip: 16",
       {"landmarks.nose_tip", "vertex 16 is out of range", "16 vertices"}},
      {"eye range", "left: [10, 11]", "left: [10, -1]", {"eyes.left[1]", "vertex -1 is out of range"}},
      {"shapes value", "shapes: absolute", "shapes: relative", {"shapes", "\"absolute\" or \"offsets\""}},
      {"bad landmark", "nose_tip: 5", "nose_tip: tip", {"landmarks.nose_tip", "tip"}},
  };
  for (const Case& c : cases) {
    INFO(c.what);
    const std::string path = variant(dir, "bad.yaml", c.from, c.to);
    try {
      load_face_model(path);
      FAIL("no error");
    } catch (const Error& e) {
      const std::string message = e.what();
      CHECK_THAT(message, Catch::Contains("bad.yaml") || Catch::Contains(".obj"));
      for (const std::string& part : c.message) CHECK_THAT(message, Catch::Contains(part));
    }
  }
  CHECK_THROWS_WITH(load_face_model((dir / "none.yaml").string()),
                    Catch::Contains("none.yaml") && Catch::Contains("not found"));
}

TEST_CASE("expression recipes load, and bad ones are refused with the entry", "[face_model]") {
  const auto dir = test::scratch_dir("face_model_recipes");
  const auto recipes = load_expression_recipes(
      write_text(dir, "r.yaml",
                 "recipes:\n  - {name: neutral, weights: {}}\n  - {name: smile, weights: {smile_L: 1, smile_R: 0.5}}\n"
                 "  - {name: rest}\n"));
  REQUIRE(recipes.size() == 3);
  CHECK(recipes[0].weights.empty());
  CHECK(recipes[1].name == "smile");
  CHECK(recipes[1].weights.at("smile_R") == 0.5);
  CHECK(recipes[2].weights.empty());

  struct Case {
    const char* text;
    std::vector<std::string> message;
  };
  const std::vector<Case> cases = {
      {"recipes:\n  - {name: a, weights: {x: 1}}\n  - {name: a, weights: {y: 1}}\n",
       {"recipes[1].name", "duplicate recipe name \"a\"", "also recipes[0]"}},
      {"recipes:\n  - {name: a, weights: {x: fast}}\n", {"recipes[0].weights.x", "fast"}},
      {"recipes:\n  - {name: a, weights: {x: .inf}}\n", {"recipes[0].weights.x", "finite"}},
      {"recipes:\n  - {name: a, weights: [1, 2]}\n", {"recipes[0].weights", "expected a map"}},
      {"recipes:\n  - {name: a, weight: {x: 1}}\n", {"recipes[0]", "weight", "unknown key"}},
      {"recipes: []\n", {"recipes", "at least one recipe"}},
      {"recipe: []\n", {"recipe", "unknown key"}},
  };
  for (const Case& c : cases) {
    INFO(c.text);
    CHECK_THROWS_WITH(load_expression_recipes(write_text(dir, "bad.yaml", c.text)), Catch::Contains("bad.yaml"));
    for (const std::string& part : c.message)
      CHECK_THROWS_WITH(load_expression_recipes(write_text(dir, "bad.yaml", c.text)), Catch::Contains(part));
  }
}

TEST_CASE("the bundled FaceWarehouse recipes load", "[face_model]") {
  const auto recipes =
      load_expression_recipes(std::string(RETARGET_SOURCE_DIR) + "/configs/expressions/facewarehouse47.yaml");
  CHECK(recipes.size() == 47);
  CHECK(recipes[0].name == "neutral");
  CHECK(recipes[0].weights.empty());
}
