// infer/gltf_animation.h and infer/weights_csv.h: an animation written and read back with the
// project's own glTF rig loader (mesh and morph targets) and with tinygltf (the animation).
#include "infer/gltf_animation.h"

#include <tiny_gltf.h>

#include <cstring>
#include <limits>

#include "geometry/rig.h"
#include "infer/weights_csv.h"
#include "tests/infer/gltf_test_support.h"
#include "tests/test_support.h"
#include "tests/tiny_animation.h"

namespace retarget::test {
// Named, not anonymous: a unity build (RETARGET_UNITY) shares one anonymous namespace per batch.
namespace gltf_animation_test {

constexpr double kFloat = 1e-6;  // relative: what float storage keeps of a double

void check_rig_matches(const Rig& rig, const GltfAnimationInput& in, double scale) {
  REQUIRE(rig.neutral.vertex_count() == in.neutral.vertex_count());
  REQUIRE(rig.neutral.triangle_count() == in.neutral.triangle_count());
  CHECK(rig.neutral.triangles == in.neutral.triangles);
  const double size = in.neutral.vertices.cwiseAbs().maxCoeff() * scale;
  CHECK((rig.neutral.vertices - in.neutral.vertices * scale).cwiseAbs().maxCoeff() <= kFloat * size);
  REQUIRE(rig.controller_count() == static_cast<int>(in.controllers.size()));
  for (int c = 0; c < rig.controller_count(); ++c) {
    CHECK(rig.controllers[c].name == in.controllers[c]);
    CHECK((rig.controllers[c].offset - in.offsets[c] * scale).cwiseAbs().maxCoeff() <= kFloat * size);
  }
}

void check_animation(const tinygltf::Model& model, const GltfAnimationInput& in, const std::vector<double>& times) {
  REQUIRE(model.animations.size() == 1);
  REQUIRE(model.nodes.size() == 1);
  REQUIRE(model.scenes.size() == 1);
  CHECK(model.scenes[0].nodes == std::vector<int>{0});
  CHECK(model.nodes[0].mesh == 0);
  const tinygltf::Mesh& mesh = model.meshes.at(0);
  CHECK(mesh.weights == std::vector<double>(in.controllers.size(), 0.0));
  REQUIRE(mesh.primitives.size() == 1);
  const tinygltf::Primitive& primitive = mesh.primitives[0];
  CHECK(primitive.attributes.count("NORMAL") == 1);
  CHECK(model.accessors.at(primitive.attributes.at("POSITION")).minValues.size() == 3);
  CHECK(model.accessors.at(primitive.attributes.at("POSITION")).maxValues.size() == 3);
  for (const auto& target : primitive.targets) {
    CHECK(model.accessors.at(target.at("POSITION")).minValues.size() == 3);
    CHECK(model.accessors.at(target.at("POSITION")).maxValues.size() == 3);
  }
  // Unit normals, facing +z on this patch (a bump over the xy plane, faces counter-clockwise).
  const std::vector<float> normals = gltf_floats(model, primitive.attributes.at("NORMAL"));
  for (size_t i = 0; i < normals.size(); i += 3) {
    CHECK(std::hypot(normals[i], normals[i + 1], normals[i + 2]) == Approx(1).margin(1e-6));
    CHECK(normals[i + 2] > 0);
  }

  const tinygltf::Animation& animation = model.animations[0];
  REQUIRE(animation.channels.size() == 1);
  CHECK(animation.channels[0].target_node == 0);
  CHECK(animation.channels[0].target_path == "weights");
  const tinygltf::AnimationSampler& sampler = animation.samplers.at(animation.channels[0].sampler);
  CHECK(sampler.interpolation == "LINEAR");
  const tinygltf::Accessor& input = model.accessors.at(sampler.input);
  REQUIRE(input.minValues.size() == 1);
  CHECK(input.minValues[0] == Approx(times.front()));
  CHECK(input.maxValues[0] == Approx(times.back()));
  const std::vector<float> t = gltf_floats(model, sampler.input);
  const std::vector<float> w = gltf_floats(model, sampler.output);
  REQUIRE(t.size() == in.weights.size());
  const size_t c = in.controllers.size();
  REQUIRE(w.size() == in.weights.size() * c);
  for (size_t f = 0; f < t.size(); ++f) {
    CHECK(t[f] == static_cast<float>(times[f]));
    for (size_t k = 0; k < c; ++k) CHECK(w[f * c + k] == static_cast<float>(in.weights[f](k)));
  }
}

}  // namespace gltf_animation_test

TEST_CASE("gltf_animation: a .glb reads back as the rig and its animation", "[gltf_animation]") {
  using namespace gltf_animation_test;
  const auto dir = scratch_dir("gltf_animation_glb");
  const GltfAnimationInput in = tiny_animation();
  GltfAnimationOptions options;
  options.fps = 10;
  const std::string path = (dir / "anim.glb").string();
  const GltfAnimationSummary summary = write_gltf_animation(in, options, path);
  CHECK(summary.frames == 7);
  CHECK(summary.controllers == 3);
  CHECK(summary.vertices == 20);
  CHECK(summary.triangles == 24);
  CHECK(summary.scale_to_metres == 0.01);  // the input is in cm
  CHECK(summary.duration == Approx(0.6));
  CHECK(summary.bytes == std::filesystem::file_size(path));

  const Rig rig = load_rig(path);
  CHECK(rig.units == "m");
  check_rig_matches(rig, in, 0.01);
  std::vector<double> times;
  for (int f = 0; f < 7; ++f) times.push_back(f / 10.0);
  check_animation(load_gltf_model(path), in, times);
  // Nothing but the file is left behind (atomic write).
  CHECK(std::distance(std::filesystem::directory_iterator(dir), std::filesystem::directory_iterator()) == 1);
}

TEST_CASE("gltf_animation: a .gltf with explicit times and scale", "[gltf_animation]") {
  using namespace gltf_animation_test;
  const auto dir = scratch_dir("gltf_animation_gltf");
  GltfAnimationInput in = tiny_animation(4);
  in.times = {0.0, 0.04, 0.5, 2.25};
  GltfAnimationOptions options;
  options.scale_to_metres = 1;  // keep the coordinates
  const std::string path = (dir / "anim.GLTF").string();
  write_gltf_animation(in, options, path);
  // JSON with the buffer inside: one file, no .bin beside it.
  std::ifstream file(path);
  const std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  CHECK(text.find("\"uri\": \"data:application/octet-stream;base64,") != std::string::npos);
  CHECK(text.find("\"targetNames\"") != std::string::npos);
  check_rig_matches(load_rig(path), in, 1.0);
  check_animation(load_gltf_model(path), in, in.times);
}

TEST_CASE("gltf_animation: units decide the scale unless it is given", "[gltf_animation]") {
  using namespace gltf_animation_test;
  GltfAnimationOptions options;
  CHECK(gltf_scale_to_metres("cm", options) == 0.01);
  CHECK(gltf_scale_to_metres("mm", options) == 0.001);
  CHECK(gltf_scale_to_metres("m", options) == 1);
  CHECK(gltf_scale_to_metres("", options) == 1);
  CHECK(error_of([&] { gltf_scale_to_metres("furlong", options); }) ==
        "gltf_animation.scale_to_metres: the mesh's units \"furlong\" are not cm, mm or m; give the metres per unit");
  options.scale_to_metres = 0.0254;
  CHECK(gltf_scale_to_metres("furlong", options) == 0.0254);
}

TEST_CASE("gltf_animation: the input from a rig", "[gltf_animation]") {
  using namespace gltf_animation_test;
  const auto dir = scratch_dir("gltf_animation_rig");
  const GltfAnimationInput in = tiny_animation(3);
  Rig rig;
  rig.neutral = in.neutral;
  rig.units = "mm";
  for (size_t c = 0; c < in.controllers.size(); ++c) rig.controllers.push_back({in.controllers[c], in.offsets[c]});
  const GltfAnimationInput from_rig = gltf_animation_input(rig, in.weights);
  CHECK(from_rig.units == "mm");
  CHECK(from_rig.controllers == in.controllers);
  const std::string path = (dir / "anim.glb").string();
  CHECK(write_gltf_animation(from_rig, {}, path).scale_to_metres == 0.001);
  check_rig_matches(load_rig(path), in, 0.001);
}

TEST_CASE("gltf_animation: bad input is refused, naming what is wrong", "[gltf_animation]") {
  using namespace gltf_animation_test;
  const auto dir = scratch_dir("gltf_animation_errors");
  const std::string path = (dir / "anim.glb").string();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Case {
    const char* what;
    std::function<void(GltfAnimationInput&, GltfAnimationOptions&)> change;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"fps 0", [](auto&, auto& o) { o.fps = 0; },
       "gltf_animation.fps: expected frames per second from 0.001 to 100000, got 0"},
      {"fps 1e-300 (times beyond a float)", [](auto&, auto& o) { o.fps = 1e-300; },
       "gltf_animation.fps: expected frames per second from 0.001 to 100000, got 1e-300"},
      {"fps nan", [nan](auto&, auto& o) { o.fps = nan; },
       "gltf_animation.fps: expected frames per second from 0.001 to 100000, got nan"},
      {"a weight beyond a float", [](auto& in, auto&) { in.weights[3](0) = 1e308; },
       path + ": frame 3: the weight 1e+308 of controller \"jawOpen\" is beyond what glTF's 32-bit floats hold"},
      {"a time beyond a float", [](auto& in, auto&) { in.times = {0, 1, 2, 3, 4, 5, 1e300}; },
       path + ": frame 6: the time 1e+300 s is beyond what glTF's 32-bit floats hold"},
      {"negative scale", [](auto&, auto& o) { o.scale_to_metres = -1; },
       "gltf_animation.scale_to_metres: expected a positive number of metres per unit (0.01 for cm), got -1"},
      {"empty mesh", [](auto& in, auto&) { in.neutral = Mesh(); }, path + ": the neutral mesh has no vertices"},
      {"no faces", [](auto& in, auto&) { in.neutral = mesh_from_triangles(in.neutral.vertices, Triangles(0, 3)); },
       path + ": the neutral mesh has no faces"},
      {"a frame too short", [](auto& in, auto&) { in.weights[4].conservativeResize(2); },
       path + ": frame 4 has 2 weights but there are 3 controllers"},
      {"a non-finite weight", [nan](auto& in, auto&) { in.weights[2](1) = nan; },
       path + ": frame 2: the weight of controller \"smile Left\" is not finite (nan)"},
      {"no frames", [](auto& in, auto&) { in.weights.clear(); }, path + ": no frames of weights"},
      {"offsets missing", [](auto& in, auto&) { in.offsets.pop_back(); },
       path + ": 3 controller names but 2 offsets; give one offset per controller"},
      {"offsets of another mesh", [](auto& in, auto&) { in.offsets[1] = Positions::Zero(5, 3); },
       path + ": controller \"smile Left\": offsets for 5 vertices, but the neutral mesh has 20"},
      {"non-finite offsets", [nan](auto& in, auto&) { in.offsets[0](3, 2) = nan; },
       path + ": controller \"jawOpen\" has non-finite offsets"},
      {"duplicate names", [](auto& in, auto&) { in.controllers[2] = "jawOpen"; },
       path + ": controller name \"jawOpen\" appears twice"},
      {"no controllers",
       [](auto& in, auto&) {
         in.controllers.clear();
         in.offsets.clear();
       },
       path + ": no controllers: a morph-target animation needs at least one"},
      {"times of another length",
       [](auto& in, auto&) {
         in.times = {0, 1};
       },
       path + ": 2 times for 7 frames; give one time per frame (or none, to use fps)"},
      {"times going back", [](auto& in, auto&) { in.times = {0, 1, 2, 3, 3, 4, 5}; },
       path + ": frame 4: time 3 s does not come after frame 3's 3 s; times must increase"},
      {"a negative time", [](auto& in, auto&) { in.times = {-1, 1, 2, 3, 4, 5, 6}; },
       path + ": frame 0: time -1 s; expected a finite number of seconds >= 0"},
      {"times equal as floats", [](auto& in, auto&) { in.times = {0, 1, 2, 3, 4, 5, 5 + 1e-9}; },
       path + ": frames 5 and 6 (5 s and 5.000000001 s) are the same time once stored as float; glTF needs "
              "strictly increasing times"},
      {"unknown units", [](auto& in, auto&) { in.units = "inch"; },
       "gltf_animation.scale_to_metres: the mesh's units \"inch\" are not cm, mm or m; give the metres per unit"},
  };
  for (const Case& c : cases) {
    INFO(c.what);
    GltfAnimationInput in = tiny_animation();
    GltfAnimationOptions options;
    c.change(in, options);
    CHECK(error_of([&] { write_gltf_animation(in, options, path); }) == c.message);
  }
  CHECK(error_of([&] { write_gltf_animation(tiny_animation(), {}, (dir / "anim.fbx").string()); }) ==
        (dir / "anim.fbx").string() +
            ": expected a file name ending in .glb (binary glTF) or .gltf (JSON, buffer embedded)");
  CHECK(!std::filesystem::exists(path));
}

TEST_CASE("weights_csv: the table retarget-infer --weights writes", "[weights_csv]") {
  const auto dir = scratch_dir("weights_csv");
  const std::string path = write_file(dir / "weights.csv",
                                      "\xEF\xBB\xBF"
                                      "frame,jawOpen,\"smile, left\",\"say \"\"o\"\"\",residual_mm\r\n"
                                      "take_0001,0.25,0,1,0.125\r\n"
                                      "\r\n"
                                      "\"a, b\",-0.5, 1e-3 ,0.75,nan\n");
  const WeightsCsv csv = read_weights_csv(path);
  CHECK(csv.controllers == std::vector<std::string>{"jawOpen", "smile, left", "say \"o\""});
  CHECK(csv.frames == std::vector<std::string>{"take_0001", "a, b"});
  REQUIRE(csv.weights.size() == 2);
  CHECK(csv.weights[0] == Eigen::Vector3d(0.25, 0, 1));
  CHECK(csv.weights[1] == Eigen::Vector3d(-0.5, 1e-3, 0.75));
  REQUIRE(csv.residual_mm.size() == 2);
  CHECK(csv.residual_mm[0] == 0.125);
  CHECK(std::isnan(csv.residual_mm[1]));

  CHECK_NOTHROW(require_weights_controllers(csv, {"jawOpen", "smile, left", "say \"o\""}));
  CHECK(error_of([&] {
          require_weights_controllers(csv, {"jawOpen", "smileLeft", "say \"o\""});
        }) == path +
                  ": column 3 is \"smile, left\" but the rig's controller 2 is \"smileLeft\"; the columns must be the "
                  "rig's controllers in its order");
  CHECK(error_of([&] {
          require_weights_controllers(csv, {"jawOpen", "smile, left"});
        }) ==
        path + ": 3 controller columns but the rig has 2 controllers; the file has an extra column \"say \"o\"\"");
  CHECK(error_of([&] {
          require_weights_controllers(csv, {"jawOpen", "smile, left", "say \"o\"", "blink"});
        }) ==
        path + ": 3 controller columns but the rig has 4 controllers; the file lacks the rig's controller \"blink\"");

  // Without residual_mm, every column after `frame` is a controller.
  const WeightsCsv bare = read_weights_csv(write_file(dir / "bare.csv", "frame,a,b\n0,1,2\n1,3,4\n"));
  CHECK(bare.controllers == std::vector<std::string>{"a", "b"});
  CHECK(bare.residual_mm.empty());
  CHECK(bare.weights.size() == 2);
}

TEST_CASE("weights_csv: bad files are refused with file and line", "[weights_csv]") {
  const auto dir = scratch_dir("weights_csv_errors");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", ": empty: expected a header frame,<controller names...>,residual_mm"},
      {"time,a\n0,1\n",
       ":1: the header should start with \"frame\", got \"time\" (expected frame,<controller names...>,residual_mm)"},
      {"frame,residual_mm\n0,1\n", ":1: the header names no controller column"},
      {"frame,a,a\n0,1,2\n", ":1: column \"a\" appears twice"},
      {"frame,a,,b\n0,1,2,3\n", ":1: column 3 has no name"},
      {"frame,a,b\n0,1,2\n1,2\n", ":3: 2 fields, but the header has 3 columns"},
      {"frame,a,b\n\n0,1,x\n", ":3: column \"b\": expected a finite number, got \"x\""},
      {"frame,a,b\n0,1,inf\n", ":2: column \"b\": expected a finite number, got \"inf\""},
      {"frame,a,b\n", ": no rows of weights after the header"},
      {"frame,a,b\n0,\"1,2\n", ":2: a quoted field is never closed"},
      {"frame,a,residual_mm\n0,1,low\n", ":2: column \"residual_mm\": expected a number, got \"low\""},
      {"frame,a,b\n0,1,1e308\n",
       ":2: column \"b\": the weight 1e308 is out of range: a controller weight is within +-1000 (rigs' ranges are "
       "about [0, 1])"},
      {"frame,a,b\n0,1,-1001\n",
       ":2: column \"b\": the weight -1001 is out of range: a controller weight is within +-1000 (rigs' ranges are "
       "about [0, 1])"},
      {std::string("frame,a,b\n0,1,0.\0\n", 18),
       ": line 2, column 7: byte 0x00 is not text; a weights file is CSV text (is this a binary file?)"},
      {"frame,a,b\n0,\xff\xfe,1\n",
       ": line 2, column 3: byte 0xFF is not text; a weights file is CSV text (is this a binary file?)"},
  };
  for (const auto& [text, message] : cases) {
    INFO(text);
    const std::string path = write_file(dir / "w.csv", text);
    CHECK(error_of([&] { read_weights_csv(path); }) == path + message);
  }
  CHECK(error_of([&] { read_weights_csv((dir / "missing.csv").string()); }) ==
        (dir / "missing.csv").string() + ": cannot open the weights file");
}

}  // namespace retarget::test
