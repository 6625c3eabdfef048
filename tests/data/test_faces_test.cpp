// Tests for data/test_faces.h: the held-out people's meshes as files.
#include "data/test_faces.h"

#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "data/dataset.h"
#include "geometry/face_model.h"
#include "geometry/mesh_io.h"
#include "tiny_data.h"

using namespace retarget;
namespace fs = std::filesystem;

namespace {

// A face model and recipes on disk (the dataset records their paths) and a dataset built from them.
struct FaceFiles {
  std::string model, recipes, dataset;
};

const FaceFiles& face_files() {
  static const FaceFiles files = [] {
    const fs::path dir = test::process_scratch_dir("test_faces_data");
    write_face_model((dir / "model").string(), test::tiny_face_model());
    FaceFiles f{(dir / "model" / "face_model.yaml").string(), (dir / "recipes.yaml").string(), (dir / "data").string()};
    std::ofstream(f.recipes) << "recipes:\n  - {name: neutral, weights: {}}\n  - {name: A, weights: {a: 1.0}}\n"
                                "  - {name: AB, weights: {a: 0.5, b: 1.0}}\n";
    HumanDatasetOptions o;
    o.people = 6;
    o.test_people = 2;
    o.seed = 3;
    o.progress = nullptr;
    build_human_dataset(load_face_model(f.model), load_expression_recipes(f.recipes), f.recipes, f.dataset, o);
    return f;
  }();
  return files;
}

}  // namespace

TEST_CASE("write_test_faces writes each held-out person's expressions, as the face model builds them") {
  const FaceFiles& f = face_files();
  const Dataset d = load_dataset(f.dataset);
  const FaceModel model = load_face_model(f.model);
  const fs::path out = test::scratch_dir("test_faces_out");
  const TestFaces written = write_test_faces(f.dataset, out.string());
  REQUIRE(written.faces.size() == d.test_subjects.size() * d.expressions.size());

  const TestFaces read = load_test_faces(out.string());
  REQUIRE(read.faces.size() == written.faces.size());
  CHECK(read.fingerprint == d.fingerprint);
  CHECK(read.recipes == d.recipes);
  for (size_t i = 0; i < read.faces.size(); ++i) {
    const TestFace& face = read.faces[i];
    CHECK(face.file == face.subject + "_" + face.expression + ".obj");
    CHECK(std::find(d.test_subjects.begin(), d.test_subjects.end(), face.subject) != d.test_subjects.end());
    CHECK(face.weights == written.faces[i].weights);
    const int p = static_cast<int>(std::find(d.subjects.begin(), d.subjects.end(), face.subject) - d.subjects.begin());
    const torch::Tensor row = d.identity[p].contiguous();
    const Eigen::VectorXd c = Eigen::Map<const Eigen::VectorXd>(row.data_ptr<double>(), row.size(0));
    const Positions expected = model.expression(model.person(c), face.weights);
    const Mesh mesh = read_mesh((out / face.file).string());
    CHECK((mesh.vertices - expected).cwiseAbs().maxCoeff() < 1e-5);
    CHECK(mesh.triangles == d.rest.triangles);
  }
  const auto ab =
      std::find_if(read.faces.begin(), read.faces.end(), [](const TestFace& t) { return t.expression == "AB"; });
  REQUIRE(ab != read.faces.end());
  CHECK(ab->weights == std::map<std::string, double>{{"a", 0.5}, {"b", 1.0}});
}

TEST_CASE("write_test_faces picks subjects and expressions and refuses what it does not know") {
  const FaceFiles& f = face_files();
  const Dataset d = load_dataset(f.dataset);
  const fs::path out = test::scratch_dir("test_faces_pick");
  TestFacesOptions o;
  o.split = "train";
  o.subjects = {d.train_subjects.front()};
  o.expressions = {"A"};
  const TestFaces one = write_test_faces(f.dataset, out.string(), o);
  REQUIRE(one.faces.size() == 1);
  CHECK(one.faces[0].subject == d.train_subjects.front());

  // The folder is no longer empty.
  CHECK_THROWS_WITH(write_test_faces(f.dataset, out.string(), o), Catch::Contains("--force"));
  o.force = true;
  o.expressions = {"smile"};
  CHECK_THROWS_WITH(write_test_faces(f.dataset, out.string(), o),
                    Catch::Contains("unknown expression 'smile'") && Catch::Contains("neutral, A, AB"));
  o.expressions = {};
  o.subjects = {d.test_subjects.front()};  // not a training subject
  CHECK_THROWS_WITH(write_test_faces(f.dataset, out.string(), o), Catch::Contains("unknown subject"));
  o.split = "everyone";
  CHECK_THROWS_WITH(write_test_faces(f.dataset, out.string(), o), Catch::Contains("faces.split"));
}

TEST_CASE("load_test_faces names the file and key of a malformed faces.yaml") {
  const fs::path dir = test::scratch_dir("test_faces_bad");
  CHECK_THROWS_WITH(load_test_faces(dir.string()), Catch::Contains("has no faces.yaml"));
  std::ofstream(dir / "faces.yaml") << "format: retarget-faces\ndataset: d\nfingerprint: f\n"
                                       "faces:\n  - {file: ../escape.obj, subject: s, expression: e}\n";
  CHECK_THROWS_WITH(load_test_faces(dir.string()), Catch::Contains("faces.yaml:5") && Catch::Contains("faces[0].file"));
}

TEST_CASE("write_test_faces adds random blends beside the references, the same for every person") {
  const FaceFiles& f = face_files();
  const Dataset d = load_dataset(f.dataset);
  const FaceModel model = load_face_model(f.model);
  const fs::path out = test::scratch_dir("test_faces_blends");
  TestFacesOptions o;
  o.blends.count = 5;
  o.blends.seed = 11;
  const TestFaces written = write_test_faces(f.dataset, out.string(), o);
  REQUIRE(written.faces.size() == d.test_subjects.size() * (d.expressions.size() + 5));
  CHECK(written.sets() == std::vector<std::string>{kReferenceSet, kBlendSet});

  const TestFaces read = load_test_faces(out.string());
  std::map<std::string, std::map<std::string, double>> blend_weights;  // the same blend for everyone
  int blends = 0;
  for (const TestFace& face : read.faces) {
    if (face.set != kBlendSet) {
      CHECK(face.set == kReferenceSet);
      continue;
    }
    ++blends;
    CHECK(face.expression.rfind("blend", 0) == 0);
    REQUIRE_FALSE(face.weights.empty());
    const auto [it, fresh] = blend_weights.emplace(face.expression, face.weights);
    if (!fresh) CHECK(it->second == face.weights);
    // The mesh is the face model's own blend of that person.
    const int p = static_cast<int>(std::find(d.subjects.begin(), d.subjects.end(), face.subject) - d.subjects.begin());
    const torch::Tensor row = d.identity[p].contiguous();
    const Eigen::VectorXd c = Eigen::Map<const Eigen::VectorXd>(row.data_ptr<double>(), row.size(0));
    const Mesh mesh = read_mesh((out / face.file).string());
    CHECK((mesh.vertices - model.expression(model.person(c), face.weights)).cwiseAbs().maxCoeff() < 1e-5);
  }
  CHECK(blends == static_cast<int>(d.test_subjects.size()) * 5);
  CHECK(blend_weights.size() == 5);

  // Blends only: each person's neutral stays for deformation transfer.
  o.references = false;
  o.force = true;
  const TestFaces only = write_test_faces(f.dataset, out.string(), o);
  REQUIRE(only.faces.size() == d.test_subjects.size() * 6);
  int neutrals = 0;
  for (const TestFace& face : only.faces) neutrals += face.expression == "neutral";
  CHECK(neutrals == static_cast<int>(d.test_subjects.size()));

  // A set the reader does not know is named with its line.
  std::ofstream(out / "faces.yaml") << "format: retarget-faces\ndataset: d\nfingerprint: f\n"
                                       "faces:\n  - {file: a.obj, subject: s, expression: e, set: mixed}\n";
  CHECK_THROWS_WITH(load_test_faces(out.string()), Catch::Contains("faces.yaml:5") && Catch::Contains("set"));
}
