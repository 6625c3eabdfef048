// retarget-infer --rig-map: the rig head at inference, on a bundle with a rig, a face model and an
// ARKit take or the model's own faces as meshes.
#include "infer/rig_head_run.h"

#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "bundle/bundle_format.h"
#include "geometry/controller_map.h"
#include "geometry/face_model_fit.h"
#include "geometry/mesh_io.h"
#include "infer/arkit_faces.h"
#include "infer/arkit_take.h"
#include "infer/weights_csv.h"
#include "tests/infer/arkit_test_support.h"

namespace retarget {
namespace rig_head_run_test {

namespace fs = std::filesystem;

struct Scene {
  fs::path dir;
  std::string bundle, face_model, take, map;
  Rig rig;
  FaceModel model = test::arkit_test_model();
  ControllerMap controller_map;

  explicit Scene(const std::string& name) : dir(test::scratch_dir(name)), bundle(test::tiny_rig_bundle(dir / "b")) {
    write_face_model((dir / "model").string(), model);
    face_model = (dir / "model" / "face_model.yaml").string();
    take = test::write_file(dir / "take.csv", test::live_link_csv(test::arkit_test_frames(11)));
    rig = *load_bundle(bundle).rig;
    // A map with every entry known: controller c reads shape s with weight 0.1 (c + 1) - 0.05 s.
    for (const Controller& c : rig.controllers) controller_map.controllers.push_back(c.name);
    for (const Blendshape& b : model.expressions) controller_map.shapes.push_back(b.name);
    controller_map.matrix.resize(static_cast<Eigen::Index>(controller_map.controllers.size()),
                                 static_cast<Eigen::Index>(controller_map.shapes.size()));
    for (Eigen::Index c = 0; c < controller_map.matrix.rows(); ++c)
      for (Eigen::Index s = 0; s < controller_map.matrix.cols(); ++s)
        controller_map.matrix(c, s) = 0.1 * static_cast<double>(c + 1) - 0.05 * static_cast<double>(s);
    controller_map.pairs = 47;
    map = (dir / "map.yaml").string();
    write_controller_map(map, controller_map);
  }

  RigHeadRunOptions options(const std::string& out) const {
    RigHeadRunOptions o;
    o.bundle = bundle;
    o.rig_map = map;
    o.face_model = face_model;
    o.out = (dir / out).string();
    return o;
  }
};

// weights.csv's rows, by frame name.
std::map<std::string, Eigen::VectorXd> weights_by_frame(const std::string& path) {
  const WeightsCsv csv = read_weights_csv(path);
  std::map<std::string, Eigen::VectorXd> out;
  for (size_t f = 0; f < csv.frames.size(); ++f) out[csv.frames[f]] = csv.weights[f];
  return out;
}

TEST_CASE("rig head: a take's frames through the map onto the rig, its meshes, weights and glTF", "[rig_head_run]") {
  const Scene scene("rig_head_run_take");
  RigHeadRunOptions o = scene.options("take_out");
  o.arkit = scene.take;
  o.gltf = (scene.dir / "take_out" / "anim.glb").string();
  const RigHeadRunSummary summary = run_rig_head(o);
  CHECK(summary.frames == 11);
  CHECK(summary.controllers == scene.rig.controller_count());
  CHECK(summary.pairs == 47);
  CHECK(fs::exists(scene.dir / "take_out" / "frames.csv"));
  CHECK_THAT(format_rig_head_summary(summary), Catch::Contains("rig head: 11 frames onto"));

  std::vector<std::string> names;
  for (const Blendshape& b : scene.model.expressions) names.push_back(b.name);
  const ArkitTake take = read_arkit_take(scene.take, names);
  const auto written = weights_by_frame(summary.weights_csv);
  REQUIRE(written.size() == 11);
  for (int f = 0; f < 11; ++f) {
    INFO("frame " << f);
    std::map<std::string, double> human;
    for (size_t k = 0; k < names.size(); ++k) human[names[k]] = take.weights(f, static_cast<Eigen::Index>(k));
    const Eigen::VectorXd expected = scene.controller_map.on_rig(human, scene.rig);
    const Eigen::VectorXd& got = written.at(fmt::format("frame_{:06d}", f));
    CHECK((got - expected).cwiseAbs().maxCoeff() <= 1e-5);  // 6 significant digits in the table
    // The mesh is the rig at those weights, clamped to the controllers' ranges.
    const Mesh mesh = read_mesh(summary.outputs[static_cast<size_t>(f)]);
    CHECK((mesh.vertices - scene.rig.evaluate(expected)).cwiseAbs().maxCoeff() <= 1e-5);
    for (Eigen::Index c = 0; c < expected.size(); ++c) {
      CHECK(got(c) >= scene.rig.controllers[static_cast<size_t>(c)].min - 1e-9);
      CHECK(got(c) <= scene.rig.controllers[static_cast<size_t>(c)].max + 1e-9);
    }
  }
  const Rig animated = load_rig(o.gltf);
  CHECK(animated.controller_count() == scene.rig.controller_count());
}

TEST_CASE("rig head: human meshes are read as the face model fitted to each, then mapped", "[rig_head_run]") {
  const Scene scene("rig_head_run_meshes");
  RigHeadRunOptions from_take = scene.options("from_take");
  from_take.arkit = scene.take;
  const auto from_weights = weights_by_frame(run_rig_head(from_take).weights_csv);

  // The take's frames as human meshes of the mean face, named as the take path names them.
  std::vector<std::string> names;
  for (const Blendshape& b : scene.model.expressions) names.push_back(b.name);
  const ArkitTake take = read_arkit_take(scene.take, names);
  const ArkitFaces faces(scene.model);
  fs::create_directories(scene.dir / "faces");
  for (int f = 0; f < take.frames(); ++f)
    write_mesh((scene.dir / "faces" / fmt::format("frame_{:06d}.obj", f)).string(), faces.mesh(take, f));
  RigHeadRunOptions from_meshes = scene.options("from_meshes");
  from_meshes.inputs = {(scene.dir / "faces").string()};
  const RigHeadRunSummary summary = run_rig_head(from_meshes);
  CHECK(summary.frames == take.frames());
  const auto got = weights_by_frame(summary.weights_csv);
  REQUIRE(got.size() == from_weights.size());
  const FaceModelFit fit(scene.model);
  for (int f = 0; f < take.frames(); ++f) {
    const std::string frame = fmt::format("frame_{:06d}", f);
    INFO(frame);
    // Exactly the fit, mapped: the run adds nothing of its own.
    const Eigen::VectorXd expected = scene.controller_map.on_rig(fit.fit(faces.frame(take, f)), scene.rig);
    CHECK((got.at(frame) - expected).cwiseAbs().maxCoeff() <= 1e-5);
    // And the fit finds the take's weights back, up to its conditioning (the test model's smooth
    // shapes are nearly collinear): the same controller weights within 0.01.
    CHECK((got.at(frame) - from_weights.at(frame)).cwiseAbs().maxCoeff() <= 0.01);
  }
}

TEST_CASE("rig head: a map of another rig or face model, and missing options, are refused before any work",
          "[rig_head_run]") {
  const Scene scene("rig_head_run_errors");
  RigHeadRunOptions o = scene.options("out");
  o.arkit = scene.take;
  ControllerMap other = scene.controller_map;
  other.controllers.back() = "tailWag";
  write_controller_map((scene.dir / "other_rig.yaml").string(), other);
  o.rig_map = (scene.dir / "other_rig.yaml").string();
  CHECK_THAT(
      test::error_of([&] { run_rig_head(o); }),
      Catch::Contains("other_rig.yaml") && Catch::Contains("not the " + std::to_string(scene.rig.controller_count())));
  other = scene.controller_map;
  other.shapes.back() = "tongueOut";
  write_controller_map((scene.dir / "other_model.yaml").string(), other);
  o.rig_map = (scene.dir / "other_model.yaml").string();
  CHECK_THAT(test::error_of([&] { run_rig_head(o); }),
             Catch::Contains("maps from the shape \"tongueOut\", which the face model"));
  CHECK_FALSE(fs::exists(scene.dir / "out" / "weights.csv"));
  // A mesh of another topology than the face model's stops the run, naming it.
  o = scene.options("out");
  const std::string sphere = (scene.dir / "sphere.obj").string();
  write_mesh(sphere, uv_sphere(5, 6));
  o.inputs = {sphere};
  CHECK_THAT(test::error_of([&] { run_rig_head(o); }), Catch::Contains(sphere) && Catch::Contains("vertices"));
  o = scene.options("out");
  CHECK(test::error_of([&] { run_rig_head(o); }) == "--arkit: give an ARKit take or human meshes to retarget");
  o.arkit = scene.take;
  o.face_model.clear();
  CHECK(test::error_of([&] { run_rig_head(o); }) ==
        "--face-model: required with --rig-map: the face model whose blendshapes the map reads");
}

TEST_CASE("retarget-infer --rig-map from the command line", "[rig_head_run][cli]") {
  const Scene scene("rig_head_run_cli");
  const fs::path log = scene.dir / "cli.log";
  const std::string common = "--bundle '" + scene.bundle + "' --rig-map '" + scene.map + "' --face-model '" +
                             scene.face_model + "' --arkit '" + scene.take + "' --out '" +
                             (scene.dir / "out").string() + "'";
  CHECK(test::run_infer_cli(common, log) == 0);
  CHECK_THAT(test::read_text(log), Catch::Contains("rig head: 11 frames onto"));
  CHECK(test::run_infer_cli(common + " --render", log) == 2);
  CHECK(test::read_text(log) ==
        "retarget-infer: --render: not with --rig-map (the rig head writes the rig's own "
        "weights, without the network)\n");
}

}  // namespace rig_head_run_test
namespace rig_head_run_test {

// The face model as a rig: one controller per expression shape, the shape's offset, range [0, 1].
BundleRig face_model_rig(const FaceModel& model) {
  BundleRig part;
  part.rig.name = "patch-rig";
  part.rig.source = "patch-rig/rig.yaml";
  part.rig.neutral = model.neutral;
  for (const Blendshape& b : model.expressions) {
    Controller c;
    c.name = b.name;
    c.offset = b.offset;
    c.min = 0;
    c.max = 1;
    part.rig.controllers.push_back(std::move(c));
  }
  part.millimetres_per_unit = 10;
  return part;
}

}  // namespace rig_head_run_test

// Blendshape animation (the paper's BS baseline, which the rig head runs) is exact when the rig's
// controllers are the face model's own shapes (as the ICT rig's are) and the table maps each
// shape to its controller: every output mesh is its input face, every weight the take's.
TEST_CASE("rig head: BS is exact when the rig's controllers are the face model's own shapes", "[rig_head_run]") {
  using namespace rig_head_run_test;
  const fs::path dir = test::scratch_dir("rig_head_run_bs_exact");
  const FaceModel model = test::arkit_test_model();
  write_face_model((dir / "model").string(), model);
  RandomBundleOptions bundle_options = test::tiny_bundle_options();
  bundle_options.rig = face_model_rig(model);
  write_random_bundle(model.neutral, model.neutral, (dir / "bundle").string(), bundle_options);
  ControllerMap identity;
  for (const Blendshape& b : model.expressions)
    identity.controllers.push_back(b.name), identity.shapes.push_back(b.name);
  identity.matrix = Eigen::MatrixXd::Identity(static_cast<Eigen::Index>(model.expressions.size()),
                                              static_cast<Eigen::Index>(model.expressions.size()));
  identity.pairs = 47;
  write_controller_map((dir / "identity.yaml").string(), identity);

  const std::string take_path = test::write_file(dir / "take.csv", test::live_link_csv(test::arkit_test_frames(9)));
  std::vector<std::string> names;
  for (const Blendshape& b : model.expressions) names.push_back(b.name);
  const ArkitTake take = read_arkit_take(take_path, names);
  const ArkitFaces faces(model);
  fs::create_directories(dir / "faces");
  for (int f = 0; f < take.frames(); ++f)
    write_mesh((dir / "faces" / fmt::format("frame_{:06d}.obj", f)).string(), faces.mesh(take, f));

  RigHeadRunOptions o;
  o.bundle = (dir / "bundle").string();
  o.rig_map = (dir / "identity.yaml").string();
  o.face_model = (dir / "model" / "face_model.yaml").string();
  o.arkit = take_path;  // the take's own weights: exact
  o.out = (dir / "from_take").string();
  const RigHeadRunSummary from_take = run_rig_head(o);
  REQUIRE(from_take.frames == take.frames());
  const double size =
      (model.neutral.vertices.colwise().maxCoeff() - model.neutral.vertices.colwise().minCoeff()).norm();
  for (int f = 0; f < take.frames(); ++f) {
    INFO("frame " << f);
    const Positions got = read_mesh(from_take.outputs[static_cast<size_t>(f)]).vertices;
    CHECK((got - faces.frame(take, f)).rowwise().norm().maxCoeff() <= 1e-5 * size);
  }
  o.arkit.clear();  // the faces as meshes: the weights fitted to each, then the same map
  o.inputs = {(dir / "faces").string()};
  o.out = (dir / "from_meshes").string();
  const RigHeadRunSummary from_meshes = run_rig_head(o);
  for (int f = 0; f < take.frames(); ++f) {
    INFO("frame " << f);
    const Positions got = read_mesh(from_meshes.outputs[static_cast<size_t>(f)]).vertices;
    // The fit is regularised and the test model's smooth shapes nearly collinear: within 1% of the size.
    CHECK((got - faces.frame(take, f)).rowwise().norm().maxCoeff() <= 1e-2 * size);
  }
}

}  // namespace retarget
