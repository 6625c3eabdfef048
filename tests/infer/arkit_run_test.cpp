// retarget-infer --arkit: takes through a face model and a bundle, against the mesh path.
#include <sys/wait.h>

// LibTorch before Catch: glog (through c10) defines CHECK, and the last definition wins.
#include <torch/torch.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "geometry/face_model.h"
#include "geometry/mesh_io.h"
#include "infer/arkit_faces.h"
#include "infer/infer_run.h"
#include "tests/infer/arkit_test_support.h"

namespace retarget {
namespace {

namespace fs = std::filesystem;

// A tiny bundle on the human patch, the patch face model on disk and a Live Link take of 11 frames.
struct ArkitScene {
  fs::path dir;
  std::string bundle, face_model, take;
  explicit ArkitScene(const std::string& name)
      : dir(test::scratch_dir(name)), bundle(test::tiny_bundle(dir / "bundle")) {
    write_face_model((dir / "model").string(), test::arkit_test_model());
    face_model = (dir / "model" / "face_model.yaml").string();
    take = test::write_file(dir / "take.csv", test::live_link_csv(test::arkit_test_frames(11)));
  }

  InferOptions options(const std::string& out) const {
    InferOptions o;
    o.bundle = bundle;
    o.arkit = take;
    o.face_model = face_model;
    o.out = (dir / out).string();
    o.batch = 4;
    o.progress = nullptr;
    return o;
  }
};

struct ArkitQuietLog {
  log::Level previous = log::level();
  ArkitQuietLog() { log::set_level(log::Level::off); }
  ~ArkitQuietLog() { log::set_level(previous); }
};

std::string arkit_frame_name(int frame) { return fmt::format("frame_{:06d}.obj", frame); }

}  // namespace

TEST_CASE(
    "run_inference with an ARKit take gives the avatar meshes of the take's human meshes run through the mesh path",
    "[arkit_run]") {
  const ArkitQuietLog quiet;
  const ArkitScene scene("arkit_run_equal");
  for (const bool mean_face : {true, false}) {
    INFO((mean_face ? "the mean face" : "a chosen identity"));
    const std::string tag = mean_face ? "mean" : "person";
    InferOptions arkit = scene.options("out_arkit_" + tag);
    if (!mean_face) arkit.identity = {0.75, -1.5};
    const InferSummary summary = run_inference(arkit);
    REQUIRE(summary.failed() == 0);
    REQUIRE(summary.done == 11);
    REQUIRE(summary.inputs == 11);

    // The mesh path: the same faces as OBJ files, through retarget-infer's mesh inputs.
    const ArkitFaces faces(load_face_model(scene.face_model),
                           Eigen::Map<const Eigen::VectorXd>(arkit.identity.data(), arkit.identity.size()));
    const ArkitTake take = read_arkit_take(scene.take, faces.expression_names());
    const fs::path humans = scene.dir / ("humans_" + tag);
    fs::create_directories(humans);
    for (int f = 0; f < take.frames(); ++f) write_mesh((humans / arkit_frame_name(f)).string(), faces.mesh(take, f));
    InferOptions meshes = arkit;
    meshes.arkit.clear();
    meshes.face_model.clear();
    meshes.identity.clear();
    meshes.inputs = {humans.string()};
    meshes.out = (scene.dir / ("out_meshes_" + tag)).string();
    const InferSummary reference = run_inference(meshes);
    REQUIRE(reference.done == 11);

    for (int f = 0; f < 11; ++f) {
      INFO("frame " << f);
      CHECK(fs::path(summary.outputs[f]).filename() == arkit_frame_name(f));
      const Mesh a = read_mesh(summary.outputs[f]), b = read_mesh(reference.outputs[f]);
      // 1e-4 mm in the avatar's units (cm or mm): at most 1e-5.
      CHECK(test::max_difference(a.vertices, b.vertices) <= 1e-5);
    }
    // The frames file: frame index and the take's timecode.
    std::string expected = "frame,timecode\n";
    for (int f = 0; f < 11; ++f) expected += fmt::format("{},{}\n", f, test::live_link_timecode(f));
    CHECK(test::read_text(fs::path(arkit.out) / "frames.csv") == expected);
  }
}

TEST_CASE("run_inference with an ARKit take and --weights: rows named by frame, as for the same faces as meshes",
          "[arkit_run][weights]") {
  const ArkitQuietLog quiet;
  const ArkitScene scene("arkit_run_weights");
  InferOptions arkit = scene.options("out_arkit");
  arkit.bundle = test::tiny_rig_bundle(scene.dir / "rig_bundle");
  arkit.weights = true;
  arkit.weights_smoothness = 0.1;  // the previous frame's weights matter: the order must be the take's
  REQUIRE(run_inference(arkit).done == 11);

  const ArkitFaces faces(load_face_model(scene.face_model));
  const ArkitTake take = read_arkit_take(scene.take, faces.expression_names());
  const fs::path humans = scene.dir / "humans";
  fs::create_directories(humans);
  for (int f = 0; f < take.frames(); ++f) write_mesh((humans / arkit_frame_name(f)).string(), faces.mesh(take, f));
  InferOptions meshes = arkit;
  meshes.arkit.clear();
  meshes.face_model.clear();
  meshes.inputs = {humans.string()};
  meshes.out = (scene.dir / "out_meshes").string();
  REQUIRE(run_inference(meshes).done == 11);

  const std::string csv = test::read_text(fs::path(arkit.out) / "weights.csv");
  CHECK(csv == test::read_text(fs::path(meshes.out) / "weights.csv"));
  CHECK(csv.find("\nframe_000000,") != std::string::npos);
  CHECK(csv.find("\nframe_000010,") != std::string::npos);
  CHECK(test::read_text(fs::path(arkit.out) / "weights.jsonl") ==
        test::read_text(fs::path(meshes.out) / "weights.jsonl"));
}

TEST_CASE("run_inference with an ARKit take: what is missing or contradicts, and a face model of another topology",
          "[arkit_run]") {
  const ArkitQuietLog quiet;
  const ArkitScene scene("arkit_run_options");
  InferOptions o = scene.options("out");
  o.face_model.clear();
  CHECK(test::error_of([&] { run_inference(o); }) ==
        "--face-model: give the face model the take's weights drive (face_model.yaml or its folder), the one the "
        "bundle's human dataset was made from; bundles do not record it");
  o = scene.options("out");
  o.inputs = {"a.obj"};
  CHECK(test::error_of([&] { run_inference(o); }) ==
        "--arkit: a take takes the place of input meshes; give the take or meshes, not both");
  o = scene.options("out");
  o.arkit.clear();
  CHECK(test::error_of([&] { run_inference(o); }) == "--face-model: only with --arkit");
  o.face_model.clear();
  o.identity = {1};
  CHECK(test::error_of([&] { run_inference(o); }) == "--identity: only with --arkit");
  o = scene.options("out");
  o.identity = {1, 2, 3};
  CHECK(test::error_of([&] { run_inference(o); }) ==
        scene.face_model + ": 3 identity coefficients given but the model has 2 identity modes");

  // A face model of another topology: refused before anything is written.
  FaceModel other = test::arkit_test_model();
  other.neutral = quad_grid(9, 12, 2.0, 2.4);
  for (Blendshape& shape : other.expressions) shape.offset = Positions::Zero(130, 3);
  other.identities.clear();
  write_face_model((scene.dir / "other").string(), other);
  o = scene.options("out_other");
  o.face_model = (scene.dir / "other").string();
  const std::string message = test::error_of([&] { run_inference(o); });
  CHECK(message.find("the face model has 130 vertices but the bundle's human rest ") != std::string::npos);
  CHECK(message.find("has 143; give the face model the bundle's human dataset was made from (--face-model)") !=
        std::string::npos);
  CHECK_FALSE(fs::exists(scene.dir / "out_other"));

  // A malformed take: its error, before anything is written.
  o = scene.options("out_bad");
  o.arkit = test::write_file(scene.dir / "bad.csv", "Timecode,JawOpen\n1,0.5\n2,x\n");
  CHECK(test::error_of([&] { run_inference(o); }) == o.arkit + ":3: column 2 (JawOpen): expected a number, got \"x\"");
  CHECK_FALSE(fs::exists(scene.dir / "out_bad"));
}

TEST_CASE("retarget-infer --arkit from the command line", "[arkit_run][cli]") {
  const ArkitScene scene("arkit_run_cli");
  const fs::path log = scene.dir / "cli.log";
  const std::string common = "--bundle '" + scene.bundle + "' --arkit '" + scene.take + "' --threads 1 ";
  const fs::path out = scene.dir / "out";
  CHECK(test::run_infer_cli(common + "--face-model '" + (scene.dir / "model").string() + "' --identity 0.5,-1 --out '" +
                                out.string() + "'",
                            log) == 0);
  const std::string text = test::read_text(log);
  INFO(text);
  CHECK(text.find("11 of 11 frames done, 0 failed") != std::string::npos);
  CHECK(text.find("not used (head and eye rotations; retargeting carries the blendshapes): HeadYaw") !=
        std::string::npos);
  CHECK(fs::exists(out / "frame_000000.obj"));
  CHECK(fs::exists(out / "frame_000010.obj"));
  CHECK(fs::exists(out / "frames.csv"));

  CHECK(test::run_infer_cli(common + "--out '" + out.string() + "'", log) == 2);
  CHECK(test::read_text(log).find("retarget-infer: --face-model: give the face model") != std::string::npos);
  CHECK(test::run_infer_cli(
            common + "--face-model '" + scene.face_model + "' --identity 1,x --out '" + out.string() + "'", log) == 2);
  CHECK(test::read_text(log) == "retarget-infer: --identity: entry 2: expected a finite number, got \"x\"\n");

  // A take whose header names no blendshape, or with a NUL inside a number: status 2, not zeros.
  const fs::path junk = scene.dir / "junk.csv";
  const std::string with_model = "--face-model '" + scene.face_model + "' --out '" + out.string() + "' --threads 1 ";
  test::write_text(junk, "Timecode,Foo,Bar\n1,0.5,0.5\n");
  CHECK(test::run_infer_cli("--bundle '" + scene.bundle + "' --arkit '" + junk.string() + "' " + with_model, log) == 2);
  CHECK_THAT(test::read_text(log),
             Catch::Matchers::Contains(junk.string() + ":1: no column of the header names an expression"));
  test::write_text(junk, std::string("Timecode,JawOpen\n1,0.\0"
                                     "5\n",
                                     24));
  CHECK(test::run_infer_cli("--bundle '" + scene.bundle + "' --arkit '" + junk.string() + "' " + with_model, log) == 2);
  CHECK_THAT(test::read_text(log), Catch::Matchers::Contains(junk.string() + ":2: column 5: byte 0x00 is not text"));
  const fs::path json = scene.dir / "junk.jsonl";
  test::write_text(json, "{\"jawOpen\": 1e999}\n");
  CHECK(test::run_infer_cli("--bundle '" + scene.bundle + "' --arkit '" + json.string() + "' " + with_model, log) == 2);
  CHECK_THAT(test::read_text(log), Catch::Matchers::Contains(json.string() + ":1: a number too large for a double"));
}

}  // namespace retarget
