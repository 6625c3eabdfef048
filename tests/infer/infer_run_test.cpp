#include "infer/infer_run.h"

#include <sys/wait.h>

// LibTorch before Catch: glog (through c10) defines CHECK, and the last definition wins.
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/cpu_threads.h"
#include "core/error.h"
#include "core/log.h"
#include "geometry/mesh_io.h"
#include "infer/weights_csv.h"
#include "infer/weights_output.h"
#include "tests/infer/gltf_test_support.h"
#include "tests/infer/infer_test_support.h"

namespace retarget {
namespace {

namespace fs = std::filesystem;

// A scratch folder with a tiny bundle in it; frames and outputs go next to it.
struct Scene {
  fs::path dir;
  std::string bundle;
  explicit Scene(const std::string& name) : dir(test::scratch_dir(name)), bundle(test::tiny_bundle(dir / "bundle")) {}

  InferOptions options(std::vector<std::string> inputs) const {
    InferOptions o;
    o.bundle = bundle;
    o.inputs = std::move(inputs);
    o.out = (dir / "out").string();
    o.progress = nullptr;
    return o;
  }
};

// Errors of skipped files are expected here; keep the test log short.
struct QuietLog {
  log::Level previous = log::level();
  QuietLog() { log::set_level(log::Level::off); }
  ~QuietLog() { log::set_level(previous); }
};

using Names = std::vector<std::string>;

Names filenames(const std::vector<std::string>& paths) {
  std::vector<std::string> out;
  for (const std::string& p : paths) out.push_back(fs::path(p).filename().string());
  return out;
}

TEST_CASE("run_inference writes the in-framework pipeline's avatar meshes, in input order", "[infer_run]") {
  const Scene scene("infer_run_equal");
  const std::vector<std::string> inputs = test::write_frames(scene.dir / "in", {10, 2, 1, 3, 11});
  const LoadedBundle bundle = load_bundle(scene.bundle);
  const Mesh avatar = test::avatar_ball();

  const auto [batch, align] = GENERATE(table<int, bool>({{2, true}, {16, true}, {3, false}}));
  // One thread: each batch written while the next one runs.
  const int threads = GENERATE(0, 1);
  INFO("batch " << batch << ", align " << align << ", threads " << threads);
  InferOptions options = scene.options({(scene.dir / "in").string()});
  options.batch = batch;
  options.align_to_rest = align;
  options.threads = threads;
  const InferSummary summary = run_inference(options);
  CHECK(summary.inputs == 5);
  CHECK(summary.done == 5);
  CHECK(summary.failed() == 0);
  CHECK_FALSE(summary.stopped);
  CHECK(summary.avatar == "ball");
  CHECK(summary.avatar_vertices == 146);
  // A folder is read in natural order; outputs keep the names.
  CHECK(filenames(summary.outputs) ==
        Names({"frame_1.obj", "frame_2.obj", "frame_3.obj", "frame_10.obj", "frame_11.obj"}));
  for (const std::string& input : inputs) {
    const fs::path output = scene.dir / "out" / fs::path(input).filename();
    INFO(output);
    REQUIRE(fs::is_regular_file(output));
    const Mesh written = read_mesh(output.string());
    CHECK(written.vertex_count() == 146);
    CHECK(written.faces.indices == avatar.faces.indices);  // the avatar's own faces
    CHECK(written.faces.offsets == avatar.faces.offsets);
    const Positions expected = test::expected_output(bundle, read_mesh(input).vertices, align);
    CHECK(test::max_difference(written.vertices, expected) <= 1e-4);
  }
  const InferTimings& t = summary.seconds;
  CHECK(t.total >= t.setup + t.read + t.features + t.network + t.reconstruction + t.write);
  CHECK(t.network > 0);
  CHECK(t.render == 0);
  const std::string text = format_summary(summary);
  CHECK_THAT(text, Catch::Contains("5 of 5 files done, 0 failed") && Catch::Contains("frames/s") &&
                       Catch::Contains("DR features") && Catch::Contains("reconstruction"));
}

TEST_CASE("run_inference reports inputs of another topology and unreadable files, and goes on", "[infer_run]") {
  const QuietLog quiet;
  const Scene scene("infer_run_skips");
  const std::vector<std::string> good = test::write_frames(scene.dir / "in", {1, 2, 3});
  const std::string sphere = (scene.dir / "in" / "sphere.obj").string();
  write_mesh(sphere, uv_sphere(5, 6));  // 26 vertices
  const Mesh patch = test::human_patch();
  const std::string triangles = (scene.dir / "in" / "triangles.obj").string();
  write_mesh(triangles, mesh_from_triangles(patch.vertices, patch.triangles));  // 143 vertices, 240 faces
  const std::string broken = (scene.dir / "in" / "broken.obj").string();
  test::write_text(broken, "v 0 0 0\nf 1 2 3\n");
  const std::string missing = (scene.dir / "in" / "missing.obj").string();

  InferOptions options = scene.options({good[0], sphere, good[1], triangles, broken, missing, good[2]});
  options.batch = 3;
  const InferSummary summary = run_inference(options);
  CHECK(summary.inputs == 7);
  CHECK(summary.done == 3);
  REQUIRE(summary.failed() == 4);
  CHECK_FALSE(summary.stopped);
  CHECK(filenames(summary.outputs) == Names({"frame_1.obj", "frame_2.obj", "frame_3.obj"}));
  CHECK(summary.failures[0].input == sphere);
  CHECK_THAT(summary.failures[0].message,
             Catch::Contains("sphere.obj") && Catch::Contains("26 vertices") && Catch::Contains("143"));
  CHECK_THAT(summary.failures[1].message,
             Catch::Contains("triangles.obj") && Catch::Contains("240 faces") && Catch::Contains("120"));
  CHECK_THAT(summary.failures[2].message, Catch::Contains("broken.obj"));
  CHECK_THAT(summary.failures[3].message, Catch::Contains("missing.obj"));
  CHECK_FALSE(fs::exists(scene.dir / "out" / "sphere.obj"));
  CHECK_FALSE(fs::exists(scene.dir / "out" / "broken.obj"));
  CHECK_THAT(format_summary(summary), Catch::Contains("3 of 7 files done, 4 failed") &&
                                          Catch::Contains("4 inputs failed") && Catch::Contains("26 vertices"));
}

TEST_CASE("run_inference: a failed write is reported in input order while the next batch runs", "[infer_run]") {
  // Without strict, pictures or weights, a batch's meshes are written while the
  // next batch is computed; a write that fails is still reported before a later input's failed read.
  const QuietLog quiet;
  const Scene scene("infer_run_failed_write");
  const std::vector<std::string> good = test::write_frames(scene.dir / "in", {1, 2, 3, 4});
  const std::string missing = (scene.dir / "in" / "missing.obj").string();
  // frame_2.obj's output cannot replace a folder that holds a file.
  fs::create_directories(scene.dir / "out" / "frame_2.obj");
  test::write_text(scene.dir / "out" / "frame_2.obj" / "keep.txt", "x\n");
  InferOptions options = scene.options({good[0], good[1], good[2], missing, good[3]});
  options.batch = 2;
  options.threads = GENERATE(1, 2);
  const InferSummary summary = run_inference(options);
  CHECK(summary.inputs == 5);
  CHECK(summary.done == 3);
  REQUIRE(summary.failed() == 2);
  CHECK(filenames(summary.outputs) == Names({"frame_1.obj", "frame_3.obj", "frame_4.obj"}));
  CHECK_THAT(summary.failures[0].message, Catch::Contains("frame_2.obj"));
  CHECK_THAT(summary.failures[1].message, Catch::Contains("missing.obj"));
  for (const char* name : {"frame_1.obj", "frame_3.obj", "frame_4.obj"})
    CHECK(read_mesh((scene.dir / "out" / name).string()).vertex_count() == 146);
}

TEST_CASE("run_inference with strict stops at the first failing input", "[infer_run]") {
  const QuietLog quiet;
  const Scene scene("infer_run_strict");
  const std::vector<std::string> good = test::write_frames(scene.dir / "in", {1, 2, 3});
  const std::string sphere = (scene.dir / "in" / "sphere.obj").string();
  write_mesh(sphere, uv_sphere(5, 6));

  const int batch = GENERATE(1, 16);
  INFO("batch " << batch);
  fs::remove_all(scene.dir / "out");
  InferOptions options = scene.options({good[0], sphere, good[1], good[2]});
  options.strict = true;
  options.batch = batch;
  const InferSummary summary = run_inference(options);
  CHECK(summary.stopped);
  CHECK(summary.done == 1);
  REQUIRE(summary.failed() == 1);
  CHECK_THAT(summary.failures[0].message, Catch::Contains("sphere.obj") && Catch::Contains("26 vertices"));
  CHECK(fs::exists(scene.dir / "out" / "frame_1.obj"));
  CHECK_FALSE(fs::exists(scene.dir / "out" / "frame_2.obj"));
  CHECK_FALSE(fs::exists(scene.dir / "out" / "frame_3.obj"));
  CHECK_THAT(format_summary(summary), Catch::Contains("stopped there: --strict"));
}

TEST_CASE("run_inference: glob inputs in natural order, PLY output, pictures, name clashes", "[infer_run]") {
  const QuietLog quiet;
  const Scene scene("infer_run_glob");
  test::write_frames(scene.dir / "take1", {12, 1, 7});
  test::write_frames(scene.dir / "take2", {7});

  InferOptions options = scene.options({(scene.dir / "take1" / "frame_*.obj").string()});
  options.format = "ply";
  options.render = true;
  const InferSummary summary = run_inference(options);
  CHECK(summary.failed() == 0);
  CHECK(filenames(summary.outputs) == Names({"frame_1.ply", "frame_7.ply", "frame_12.ply"}));
  for (const std::string& output : summary.outputs) {
    CHECK(read_mesh(output).vertex_count() == 146);
    CHECK(fs::file_size(fs::path(output).replace_extension(".png")) > 1000);
  }
  CHECK(summary.seconds.render > 0);

  // take2/frame_7.obj would write the same output as take1/frame_7.obj.
  options = scene.options({(scene.dir / "take1").string(), (scene.dir / "take2" / "frame_7.obj").string()});
  const InferSummary clash = run_inference(options);
  CHECK(clash.done == 3);
  REQUIRE(clash.failed() == 1);
  CHECK_THAT(clash.failures[0].message,
             Catch::Contains("take2") && Catch::Contains("frame_7.obj") && Catch::Contains("would replace"));

  // A pattern or folder that gives no mesh is a failure like any other input.
  fs::create_directories(scene.dir / "empty");
  options = scene.options({(scene.dir / "take1" / "frame_1.obj").string(), (scene.dir / "nothing_*.obj").string(),
                           (scene.dir / "empty").string()});
  const InferSummary empty = run_inference(options);
  CHECK(empty.done == 1);
  REQUIRE(empty.failed() == 2);
  CHECK_THAT(empty.failures[0].message, Catch::Contains("nothing_*.obj") && Catch::Contains("matches no"));
  CHECK_THAT(empty.failures[1].message, Catch::Contains("empty") && Catch::Contains("no .obj"));
}

TEST_CASE("run_inference: a bad bundle or bad options stop before any work", "[infer_run]") {
  const Scene scene("infer_run_bad_bundle");
  const std::vector<std::string> inputs = test::write_frames(scene.dir / "in", {1});
  InferOptions options = scene.options(inputs);
  options.bundle = (scene.dir / "nowhere").string();
  CHECK_THROWS_WITH(run_inference(options), Catch::Contains("nowhere") && Catch::Contains("no such folder"));
  fs::remove(scene.dir / "bundle" / "bundle.pt");
  options.bundle = scene.bundle;
  CHECK_THROWS_WITH(run_inference(options), Catch::Contains("bundle.pt") && Catch::Contains("missing file"));
  CHECK_FALSE(fs::exists(scene.dir / "out"));

  options = scene.options(inputs);
  options.format = "stl";
  CHECK_THROWS_WITH(run_inference(options), Catch::Contains("--format") && Catch::Contains("stl"));
  options = scene.options(inputs);
  options.batch = 0;
  CHECK_THROWS_WITH(run_inference(options), Catch::Contains("--batch"));
  options = scene.options({});
  CHECK_THROWS_WITH(run_inference(options), Catch::Contains("at least one input"));
  // Thread counts: thousands of threads made a run crawl for minutes; now a bound per CPU.
  options = scene.options(inputs);
  options.threads = 100000;
  CHECK_THROWS_WITH(run_inference(options), Catch::Contains("--threads") && Catch::Contains("100000 threads") &&
                                                Catch::Contains(std::to_string(kMaxThreadsPerCpu * available_cpus())));
  options.threads = -1;
  CHECK_THROWS_WITH(run_inference(options), Catch::Contains("--threads") && Catch::Contains("expected a thread count"));
  CHECK(infer_threads(0) == available_cpus());
  CHECK(infer_threads(1) == 1);
}

TEST_CASE("retarget-infer: exit status, summary and messages", "[infer_run][cli]") {
  const Scene scene("infer_run_cli");
  const std::vector<std::string> good = test::write_frames(scene.dir / "in", {1, 2, 10});
  const std::string sphere = (scene.dir / "odd" / "sphere.obj").string();
  write_mesh(sphere, uv_sphere(5, 6));
  const fs::path log = scene.dir / "cli.log";
  const std::string bundle = "--bundle '" + scene.bundle + "' ";
  const std::string out = " --out '" + (scene.dir / "out").string() + "'";

  CHECK(test::run_infer_cli(bundle + "'" + (scene.dir / "in").string() + "'" + out + " --batch 2 --threads 1", log) ==
        0);
  std::string text = test::read_text(log);
  INFO(text);
  CHECK_THAT(text, Catch::Contains("3 of 3 files done, 0 failed") && Catch::Contains("frames/s"));
  const LoadedBundle loaded = load_bundle(scene.bundle);
  for (const std::string& input : good) {
    const Mesh written = read_mesh((scene.dir / "out" / fs::path(input).filename()).string());
    CHECK(test::max_difference(written.vertices, test::expected_output(loaded, read_mesh(input).vertices)) <= 1e-4);
  }

  CHECK(test::run_infer_cli(bundle + "'" + sphere + "' '" + (scene.dir / "in" / "frame_*.obj").string() + "'" + out,
                            log) == 1);
  text = test::read_text(log);
  CHECK_THAT(text, Catch::Contains("sphere.obj") && Catch::Contains("26 vertices") && Catch::Contains("143") &&
                       Catch::Contains("3 of 4 files done, 1 failed"));

  CHECK(test::run_infer_cli(bundle + "--strict '" + sphere + "' '" + good[0] + "'" + out, log) == 1);
  CHECK_THAT(test::read_text(log), Catch::Contains("0 of 2 files done") && Catch::Contains("--strict"));

  CHECK(test::run_infer_cli("--bundle '" + (scene.dir / "nowhere").string() + "' '" + good[0] + "'" + out, log) == 2);
  CHECK_THAT(test::read_text(log),
             Catch::Contains("retarget-infer") && Catch::Contains("nowhere") && Catch::Contains("no such folder"));
  CHECK(test::run_infer_cli(bundle + "'" + good[0] + "'" + out + " --no-align --align-to-rest", log) == 2);
  CHECK(test::run_infer_cli(bundle + "'" + good[0] + "'" + out + " --batch many", log) == 2);
  CHECK(test::read_text(log) == "retarget-infer: --batch: expected a number, got 'many' (see --help)\n");
  // Values that do not parse name their option (cxxopts alone: "Argument 'abc' failed to parse").
  CHECK(test::run_infer_cli(bundle + "'" + good[0] + "'" + out + " --threads abc", log) == 2);
  CHECK(test::read_text(log) == "retarget-infer: --threads: expected a number, got 'abc' (see --help)\n");
  CHECK(test::run_infer_cli(bundle + "'" + good[0] + "'" + out + " --batch=1e11", log) == 2);
  CHECK(test::read_text(log) ==
        "retarget-infer: --batch: expected a whole number in the option's range, got '1e11' (see --help)\n");
  CHECK(test::run_infer_cli(bundle + "'" + good[0] + "'" + out + " --fps nan", log) == 2);
  CHECK(test::read_text(log) == "retarget-infer: --fps: expected a number, got 'nan' (see --help)\n");
  CHECK(test::run_infer_cli("--help", log) == 0);
  CHECK_THAT(test::read_text(log), Catch::Contains("--bundle") && Catch::Contains("--strict"));
  CHECK(test::run_infer_cli(bundle + "'" + good[0] + "'" + out + " --threads 100000", log) == 2);
  CHECK_THAT(test::read_text(log), Catch::Contains("--threads: 100000 threads is more than"));

  // 200 flipped bytes in bundle.pt: refused by its checksum, naming the file (before: LibTorch's
  // std::runtime_error escaped main at the first forward pass).
  const fs::path damaged = scene.dir / "damaged";
  fs::copy(scene.bundle, damaged);
  std::string bytes = test::read_text(damaged / "bundle.pt");
  for (size_t i = 0; i < 200; ++i) bytes[bytes.size() / 3 + i] ^= 0x5a;
  std::ofstream(damaged / "bundle.pt", std::ios::binary | std::ios::trunc) << bytes;
  CHECK(test::run_infer_cli("--bundle '" + damaged.string() + "' '" + good[0] + "'" + out, log) == 2);
  CHECK_THAT(test::read_text(log),
             Catch::Contains("bundle.pt: its SHA-256 is") && Catch::Contains("export the bundle again"));
}

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> fields;
  std::istringstream in(line);
  for (std::string field; std::getline(in, field, ',');) fields.push_back(field);
  return fields;
}

TEST_CASE("run_inference --weights writes weights.csv and weights.jsonl, a row per frame in input order",
          "[infer_run][weights]") {
  const fs::path dir = test::process_scratch_dir("infer_run_weights");
  const std::string bundle = test::tiny_rig_bundle(dir / "bundle");
  const std::vector<std::string> inputs = test::write_frames(dir / "in", {10, 2, 1, 3, 11});
  InferOptions options;
  options.bundle = bundle;
  options.inputs = inputs;
  options.out = (dir / "out").string();
  options.progress = nullptr;
  options.weights = true;
  options.weights_smoothness = 0.1;
  options.batch = 2;  // frames cross batches; the smoothness term still sees the previous frame
  const InferSummary summary = run_inference(options);
  REQUIRE(summary.done == 5);
  CHECK(summary.weight_files ==
        std::vector<std::string>{(dir / "out" / "weights.csv").string(), (dir / "out" / "weights.jsonl").string()});
  CHECK(summary.weight_frames == 5);
  CHECK(summary.residual_unit == "mm");
  CHECK(summary.residual_max >= summary.residual_mean);
  CHECK(summary.residual_mean > 0);
  const std::string text = format_summary(summary);
  CHECK_THAT(text, Catch::Contains("weights: ") && Catch::Contains("weights.csv") && Catch::Contains("(5 frames)") &&
                       Catch::Contains("residual mean") && Catch::Contains(" mm, max "));

  const Rig rig = *load_bundle(bundle).rig;
  const std::vector<std::string> csv = test::lines_of(dir / "out" / "weights.csv");
  REQUIRE(csv.size() == 6);
  CHECK(csv[0] == "frame,bump0,bump1,bump2,bump3,bump4,shear,residual_mm");
  const std::vector<std::string> stems{"frame_10", "frame_2", "frame_1", "frame_3", "frame_11"};
  const std::vector<std::string> jsonl = test::lines_of(dir / "out" / "weights.jsonl");
  REQUIRE(jsonl.size() == 5);
  for (size_t f = 0; f < 5; ++f) {
    INFO(csv[f + 1]);
    const std::vector<std::string> row = split_csv(csv[f + 1]);
    REQUIRE(row.size() == 8);
    CHECK(row[0] == stems[f]);
    const nlohmann::json line = nlohmann::json::parse(jsonl[f]);
    CHECK(line.at("frame") == stems[f]);
    for (int k = 0; k < rig.controller_count(); ++k) {
      const double w = std::stod(row[k + 1]);
      CHECK(w >= rig.controllers[k].min);
      CHECK(w <= rig.controllers[k].max);
      CHECK(line.at("weights").at(rig.controllers[k].name).get<double>() == w);
    }
    CHECK(std::stod(row[7]) >= 0);
    CHECK(line.at("residual_mm").get<double>() == std::stod(row[7]));
  }

  // What the glTF animation reads back (infer/weights_csv.h) is what was written.
  const WeightsCsv table = read_weights_csv((dir / "out" / "weights.csv").string());
  require_weights_controllers(table, {"bump0", "bump1", "bump2", "bump3", "bump4", "shear"});
  CHECK(table.frames == stems);
  CHECK(table.residual_mm.size() == 5);

  // The mesh written is the mesh solved: its weights reproduce the row.
  WeightsOutputOptions same;
  same.smoothness = 0;
  WeightsOutput check(rig, 10, test::process_scratch_dir("infer_run_weights_check").string(), same);
  options.weights_smoothness = 0;
  options.weights_format = "csv";
  fs::remove_all(dir / "out");
  run_inference(options);
  CHECK_FALSE(fs::exists(dir / "out" / "weights.jsonl"));
  const std::vector<std::string> plain = test::lines_of(dir / "out" / "weights.csv");
  REQUIRE(plain.size() == 6);
  const FrameWeights first = check.add("frame_10", read_mesh((dir / "out" / "frame_10.obj").string()).vertices);
  const std::vector<std::string> row = split_csv(plain[1]);
  for (int k = 0; k < rig.controller_count(); ++k)
    CHECK(std::stod(row[k + 1]) == Approx(first.weights(k)).margin(1e-6));
  options.weights_format = "jsonl";
  fs::remove_all(dir / "out");
  run_inference(options);
  CHECK_FALSE(fs::exists(dir / "out" / "weights.csv"));
  CHECK(test::lines_of(dir / "out" / "weights.jsonl").size() == 5);
}

TEST_CASE("run_inference --gltf writes the solved weights as a glTF animation of the rig's morph targets",
          "[infer_run][weights][gltf]") {
  const fs::path dir = test::process_scratch_dir("infer_run_gltf");
  const std::string bundle = test::tiny_rig_bundle(dir / "bundle");
  InferOptions options;
  options.bundle = bundle;
  options.inputs = test::write_frames(dir / "in", {4, 1, 2});
  options.out = (dir / "out").string();
  options.progress = nullptr;
  options.weights = true;
  options.gltf = (dir / "anim.glb").string();
  options.fps = 24;
  const InferSummary summary = run_inference(options);
  REQUIRE(summary.done == 3);
  CHECK(summary.gltf == options.gltf);
  CHECK_THAT(format_summary(summary), Catch::Contains("animation: " + options.gltf));

  // The file holds the bundle's rig (read back by the project's own glTF rig loader) ...
  const Rig rig = *load_bundle(bundle).rig;
  const Rig back = load_rig(options.gltf);
  REQUIRE(back.controller_count() == rig.controller_count());
  for (int c = 0; c < rig.controller_count(); ++c) CHECK(back.controllers[c].name == rig.controllers[c].name);
  CHECK(back.neutral.vertex_count() == rig.neutral.vertex_count());
  // ... and plays weights.csv's rows at 24 frames a second.
  const WeightsCsv table = read_weights_csv((dir / "out" / "weights.csv").string());
  const tinygltf::Model model = test::load_gltf_model(options.gltf);
  REQUIRE(model.animations.size() == 1);
  const tinygltf::AnimationSampler& sampler = model.animations[0].samplers.at(0);
  const std::vector<float> times = test::gltf_floats(model, sampler.input);
  const std::vector<float> weights = test::gltf_floats(model, sampler.output);
  REQUIRE(times.size() == 3);
  REQUIRE(weights.size() == 3 * static_cast<size_t>(rig.controller_count()));
  for (size_t f = 0; f < 3; ++f) {
    CHECK(times[f] == Approx(f / 24.0).margin(1e-6));
    for (int c = 0; c < rig.controller_count(); ++c)
      CHECK(weights[f * rig.controller_count() + c] == Approx(table.weights[f](c)).margin(1e-6));
  }

  // Refused before any work: no --weights, another extension, no frame rate.
  fs::remove_all(dir / "out");
  InferOptions bad = options;
  bad.weights = false;
  CHECK_THROWS_WITH(run_inference(bad), Catch::Contains("--gltf") && Catch::Contains("give --weights too"));
  bad = options;
  bad.gltf = (dir / "anim.fbx").string();
  CHECK_THROWS_WITH(run_inference(bad), Catch::Contains("--gltf") && Catch::Contains(".glb or .gltf"));
  bad = options;
  bad.fps = 0;
  CHECK_THROWS_WITH(run_inference(bad), Catch::Contains("--fps"));
  CHECK_FALSE(fs::exists(dir / "out"));
}

TEST_CASE("run_inference --weights: a bundle without a rig and bad weight options stop before any work",
          "[infer_run][weights]") {
  const Scene scene("infer_run_weights_errors");
  const std::vector<std::string> inputs = test::write_frames(scene.dir / "in", {1});
  InferOptions options = scene.options(inputs);
  options.weights = true;
  CHECK_THROWS_WITH(run_inference(options), Catch::Contains("--weights") && Catch::Contains(scene.bundle) &&
                                                Catch::Contains("this bundle has no rig (format_version 3)") &&
                                                Catch::Contains("re-export it with `retarget export"));
  CHECK_FALSE(fs::exists(scene.dir / "out"));

  options.weights_ridge = -1;
  CHECK_THROWS_WITH(run_inference(options), Catch::Contains("--weights-ridge") && Catch::Contains("got -1"));
  options = scene.options(inputs);
  options.weights_smoothness = INFINITY;
  CHECK_THROWS_WITH(run_inference(options), Catch::Contains("--weights-smoothness") && Catch::Contains("finite"));
  options = scene.options(inputs);
  options.weights_format = "xml";
  CHECK_THROWS_WITH(run_inference(options), Catch::Contains("--weights-format") &&
                                                Catch::Contains("csv, jsonl or both") && Catch::Contains("xml"));
  CHECK_FALSE(fs::exists(scene.dir / "out"));
}

TEST_CASE("retarget-infer --weights: files, summary and messages", "[infer_run][cli][weights]") {
  const fs::path dir = test::process_scratch_dir("infer_run_weights_cli");
  const std::string rigged = test::tiny_rig_bundle(dir / "rigged");
  const std::string plain = test::tiny_bundle(dir / "plain");
  const std::vector<std::string> frames = test::write_frames(dir / "in", {1, 2, 3});
  const fs::path log = dir / "cli.log";
  const std::string in = " '" + (dir / "in").string() + "'";
  const std::string out = " --out '" + (dir / "out").string() + "'";

  CHECK(test::run_infer_cli("--bundle '" + rigged + "'" + in + out + " --weights --weights-smoothness 0.5", log) == 0);
  std::string text = test::read_text(log);
  INFO(text);
  CHECK_THAT(text, Catch::Contains("3 of 3 files done") && Catch::Contains("weights.csv") &&
                       Catch::Contains("weights.jsonl") && Catch::Contains("residual mean"));
  CHECK(test::lines_of(dir / "out" / "weights.csv").size() == 4);
  CHECK(test::lines_of(dir / "out" / "weights.jsonl").size() == 3);

  CHECK(test::run_infer_cli("--bundle '" + plain + "'" + in + out + " --weights", log) == 2);
  CHECK_THAT(test::read_text(log), Catch::Contains("retarget-infer: --weights") &&
                                       Catch::Contains("this bundle has no rig (format_version 3)"));
  CHECK(test::run_infer_cli("--bundle '" + rigged + "'" + in + out + " --weights --weights-ridge -0.1", log) == 2);
  CHECK_THAT(test::read_text(log), Catch::Contains("--weights-ridge: expected a finite number >= 0, got -0.1"));
  CHECK(test::run_infer_cli("--bundle '" + rigged + "'" + in + out + " --weights --weights-smoothness lots", log) == 2);
  CHECK_THAT(test::read_text(log), Catch::Contains("lots") && Catch::Contains("see --help"));
  CHECK(test::run_infer_cli("--bundle '" + rigged + "'" + in + out + " --weights --weights-format xml", log) == 2);
  CHECK_THAT(test::read_text(log), Catch::Contains("--weights-format"));
  CHECK(test::run_infer_cli("--help", log) == 0);
  CHECK_THAT(test::read_text(log), Catch::Contains("--weights-ridge") && Catch::Contains("--weights-smoothness") &&
                                       Catch::Contains("--weights-format"));
}

}  // namespace
}  // namespace retarget
