#include "geometry/rig.h"

#include <tiny_gltf.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

#include "core/error.h"
#include "geometry/gltf_builder.h"
#include "geometry/mesh_io.h"
#include "test_support.h"

namespace fs = std::filesystem;
using Catch::Contains;
using namespace retarget;
using retarget::test::GltfBuilder;
using retarget::test::triangles_primitive;

namespace {

std::string write_text(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
  return path.string();
}

// 3 x 3 vertices, 4 quads.
Mesh small_neutral() { return quad_grid(2, 2, 2.0, 2.0); }

Positions offset_a() {
  Positions d = Positions::Zero(9, 3);
  d(4, 2) = 0.5;  // the centre vertex rises
  return d;
}

Positions offset_b() {
  Positions d = Positions::Zero(9, 3);
  d.col(0).setConstant(0.25);  // everything shifts along x
  d(8, 1) = -1.0;
  return d;
}

// A rig folder: neutral.obj, a.obj, b.obj (absolute targets) and a rig.yaml with `extra`
// appended to the defaults.
fs::path rig_folder(const std::string& name, const std::string& yaml_body) {
  const fs::path dir = test::scratch_dir(name);
  const Mesh neutral = small_neutral();
  write_mesh((dir / "neutral.obj").string(), neutral);
  write_mesh((dir / "a.obj").string(), with_positions(neutral, neutral.vertices + offset_a()));
  write_mesh((dir / "b.obj").string(), with_positions(neutral, neutral.vertices + offset_b()));
  write_text(dir / "rig.yaml", yaml_body);
  return dir;
}

const char* kBasicRig =
    "neutral: neutral.obj\n"
    "controllers:\n"
    "  - {name: a, file: a.obj}\n"
    "  - {name: b, file: b.obj, range: [-1, 2]}\n";

}  // namespace

TEST_CASE("a rig folder loads absolute targets as offsets from the neutral", "[rig]") {
  const fs::path dir = rig_folder("rig_absolute", std::string(kBasicRig) +
                                                      "units: mm\n"
                                                      "landmarks: {nose_tip: 4, mouth_left: 8}\n"
                                                      "eyes: {left: [0, 1], right: [6, 7]}\n");
  for (const std::string& path : {dir.string(), (dir / "rig.yaml").string()}) {
    const Rig rig = load_rig(path);
    CHECK(rig.name == "rig_absolute");  // the folder's name by default
    CHECK(rig.units == "mm");
    CHECK(rig.source == (dir / "rig.yaml").string());
    REQUIRE(rig.controller_count() == 2);
    CHECK(rig.neutral.vertex_count() == 9);
    CHECK(rig.neutral.faces.size() == 4);
    CHECK(rig.controllers[0].name == "a");
    CHECK((rig.controllers[0].min == 0 && rig.controllers[0].max == 1));
    CHECK((rig.controllers[1].min == -1 && rig.controllers[1].max == 2));
    CHECK(rig.controllers[0].offset.isApprox(offset_a()));
    CHECK((rig.controllers[1].offset - offset_b()).cwiseAbs().maxCoeff() < 1e-15);
    CHECK(rig.controller_index("b") == 1);
    CHECK(rig.controller_index("c") == -1);
    CHECK(rig.landmarks.at("nose_tip") == 4);
    CHECK(rig.landmarks.at("mouth_left") == 8);
    CHECK(rig.eyes.left == std::vector<int>{0, 1});
    CHECK(rig.eyes.right == std::vector<int>{6, 7});
  }
}

TEST_CASE("Rig::evaluate is the neutral plus the weighted offsets", "[rig]") {
  const Rig rig = load_rig_folder(rig_folder("rig_evaluate", kBasicRig).string());
  const Mesh neutral = small_neutral();
  CHECK(rig.evaluate(Eigen::Vector2d(0, 0)) == neutral.vertices);
  const Positions p = rig.evaluate(Eigen::Vector2d(0.5, -1.0));
  const Positions expected = neutral.vertices + 0.5 * offset_a() - 1.0 * offset_b();
  CHECK((p - expected).cwiseAbs().maxCoeff() < 1e-14);
  CHECK(p(4, 2) == Approx(0.25));
  CHECK_THROWS_WITH(rig.evaluate(Eigen::Vector3d(1, 2, 3)), Contains("expected 2 controller weights, got 3"));
}

TEST_CASE("offset targets and targets with other faces use the neutral's connectivity", "[rig]") {
  const fs::path dir = test::scratch_dir("rig_offsets");
  const Mesh neutral = small_neutral();
  write_mesh((dir / "neutral.obj").string(), neutral);
  // The offset file's "positions" are the deltas; its faces are triangles, not quads.
  Triangles triangles(2, 3);
  triangles << 0, 1, 2, 3, 4, 5;
  write_mesh((dir / "sub" / "a_delta.obj").string(), mesh_from_triangles(offset_a(), triangles));
  write_text(dir / "rig.yaml",
             "name: blob\nneutral: neutral.obj\ntargets: offsets\n"
             "controllers: [{name: a, file: sub/a_delta.obj}]\n");
  const Rig rig = load_rig_folder(dir.string());
  CHECK(rig.name == "blob");
  CHECK(rig.controllers[0].offset == offset_a());
  CHECK(rig.neutral.faces.size() == 4);
  CHECK(rig.neutral.faces.degree(0) == 4);
}

TEST_CASE("write_rig_folder writes a rig that loads back the same", "[rig]") {
  Rig rig;
  rig.name = "round trip";
  rig.units = "cm";
  rig.neutral = small_neutral();
  rig.controllers = {{"smile/left", offset_a(), 0, 1},
                     {"neutral", offset_b(), -0.5, 0.75},
                     {"Neutral", 0.1 * offset_b(), 0, 1},
                     {"jaw open", -offset_a(), 0.1, 1}};
  rig.landmarks = {{"nose_tip", 4}, {"chin", 1}};
  rig.eyes = {{0, 3}, {5}};
  const fs::path dir = test::scratch_dir("rig_round_trip") / "out";
  write_rig_folder(dir.string(), rig);

  // Names are sanitised and kept unique (case-insensitively, and apart from neutral.obj).
  for (const char* file :
       {"rig.yaml", "neutral.obj", "smile_left.obj", "neutral_2.obj", "Neutral_3.obj", "jaw_open.obj"})
    CHECK(fs::exists(dir / file));
  CHECK(std::distance(fs::directory_iterator(dir), fs::directory_iterator()) == 6);  // no temporary files left

  const Rig back = load_rig(dir.string());
  CHECK(back.name == "round trip");
  CHECK(back.units == "cm");
  CHECK(back.neutral.vertices == rig.neutral.vertices);
  CHECK(back.neutral.faces.indices == rig.neutral.faces.indices);
  REQUIRE(back.controller_count() == 4);
  for (int c = 0; c < 4; ++c) {
    CAPTURE(c);
    CHECK(back.controllers[c].name == rig.controllers[c].name);
    CHECK(back.controllers[c].min == rig.controllers[c].min);
    CHECK(back.controllers[c].max == rig.controllers[c].max);
    CHECK((back.controllers[c].offset - rig.controllers[c].offset).cwiseAbs().maxCoeff() < 1e-15);
  }
  CHECK(back.landmarks == rig.landmarks);
  CHECK(back.eyes.left == rig.eyes.left);
  CHECK(back.eyes.right == rig.eyes.right);

  // A second write over the first replaces it.
  rig.controllers.resize(1);
  write_rig_folder(dir.string(), rig);
  CHECK(load_rig(dir.string()).controller_count() == 1);
}

TEST_CASE("bad rig folders say which file, which key and what is wrong", "[rig][errors]") {
  struct Case {
    const char* name;
    std::string yaml;
    std::vector<std::string> message;  // every part must appear
  };
  const std::string two = "neutral: neutral.obj\ncontrollers:\n  - {name: a, file: a.obj}\n";
  const std::vector<Case> cases = {
      {"vertex count",
       two + "  - {name: b, file: small.obj}\n",
       {"rig.yaml:4: controllers[1].file", "small.obj has 3 vertices", "neutral.obj has 9"}},
      {"duplicate",
       two + "  - {name: a, file: b.obj}\n",
       {"rig.yaml:4: controllers[1].name", "duplicate controller name \"a\"", "rig.yaml:3: controllers[0].name"}},
      {"missing target",
       two + "  - {name: b, file: nothere.obj}\n",
       {"controllers[1].file", "file not found", "nothere.obj"}},
      {"missing neutral",
       "neutral: gone/neutral.obj\ncontrollers: [{name: a, file: a.obj}]\n",
       {"rig.yaml:1: neutral", "file not found", "gone/neutral.obj"}},
      {"min >= max",
       two + "  - {name: b, file: b.obj, range: [1, 0]}\n",
       {"rig.yaml:4: controllers[1].range", "expected min < max, got [1, 0]"}},
      {"equal range", two + "  - {name: b, file: b.obj, range: [0.5, 0.5]}\n", {"controllers[1].range", "min < max"}},
      {"infinite range",
       two + "  - {name: b, file: b.obj, range: [0, .inf]}\n",
       {"controllers[1].range", "expected finite numbers", ".inf"}},
      {"nan range",
       two + "  - {name: b, file: b.obj, range: [.nan, 1]}\n",
       {"controllers[1].range", "expected finite numbers"}},
      {"range length",
       two + "  - {name: b, file: b.obj, range: [0, 1, 2]}\n",
       {"controllers[1].range", "expected [min, max], got 3 numbers"}},
      {"range text",
       two + "  - {name: b, file: b.obj, range: [0, big]}\n",
       {"controllers[1].range[1]", "expected a number, got \"big\""}},
      {"unknown top key", two + "contollers: []\n", {"rig.yaml:4: contollers", "did you mean 'controllers'"}},
      {"unknown controller key",
       two + "  - {name: b, file: b.obj, rang: [0, 1]}\n",
       {"controllers[1].rang", "did you mean 'range'"}},
      {"far-off controller key",
       two + "  - {name: b, file: b.obj, weight: 1}\n",
       {"controllers[1].weight", "known keys: name, file, range"}},
      {"landmark range",
       two + "landmarks: {nose_tip: 9}\n",
       {"rig.yaml:4: landmarks.nose_tip", "vertex 9 is out of range", "neutral.obj has 9 vertices"}},
      {"negative landmark", two + "landmarks: {nose_tip: -1}\n", {"landmarks.nose_tip", "vertex -1 is out of range"}},
      {"eye range",
       two + "eyes: {left: [0, 12], right: [3]}\n",
       {"eyes.left[1]", "vertex 12 is out of range", "9 vertices"}},
      {"eye missing", two + "eyes: {left: [0]}\n", {"eyes.right", "missing"}},
      {"eye key", two + "eyes: {left: [0], rigt: [1]}\n", {"eyes.rigt", "did you mean 'right'"}},
      {"targets mode", two + "targets: relative\n", {"targets", "expected 'absolute' or 'offsets', got \"relative\""}},
      {"no controllers", "neutral: neutral.obj\ncontrollers: []\n", {"controllers", "at least one controller"}},
      {"no neutral", "controllers: [{name: a, file: a.obj}]\n", {"neutral", "missing"}},
      {"empty name", two + "  - {name: '', file: b.obj}\n", {"controllers[1].name", "non-empty"}},
  };
  for (const Case& c : cases) {
    CAPTURE(c.name);
    const fs::path dir = rig_folder("rig_errors", c.yaml);
    write_mesh((dir / "small.obj").string(),
               mesh_from_triangles((Positions(3, 3) << 0, 0, 0, 1, 0, 0, 0, 1, 0).finished(),
                                   (Triangles(1, 3) << 0, 1, 2).finished()));
    try {
      load_rig_folder(dir.string());
      FAIL("no error thrown");
    } catch (const Error& e) {
      const std::string message = e.what();
      CAPTURE(message);
      for (const std::string& part : c.message) CHECK_THAT(message, Contains(part));
    }
  }
}

TEST_CASE("rig paths that are not rigs are refused by name", "[rig][errors]") {
  const fs::path dir = test::scratch_dir("rig_paths");
  CHECK_THROWS_WITH(load_rig((dir / "nowhere").string()),
                    Contains("nowhere") && Contains("no such rig folder, rig.yaml or glTF file"));
  CHECK_THROWS_WITH(load_rig(dir.string()), Contains("has no rig.yaml"));
  CHECK_THROWS_WITH(load_rig(write_text(dir / "face.fbx", "")), Contains("face.fbx") && Contains("unsupported"));
  CHECK_THROWS_WITH(load_rig((dir / "missing.glb").string()), Contains("missing.glb") && Contains("file not found"));
  const fs::path folder = rig_folder("rig_paths_mesh_name", kBasicRig);
  CHECK_THROWS_WITH(load_rig(folder.string(), "Head"), Contains("only selects a mesh in a glTF file"));
  // A broken target mesh: the key that named it, then the mesh reader's own message.
  write_text(folder / "a.obj", "v 0 0 0\nv 1 x 0\n");
  CHECK_THROWS_WITH(load_rig(folder.string()),
                    Contains("controllers[0].file") && Contains("a.obj:2") && Contains("malformed"));
}

// ---- glTF ----------------------------------------------------------------------------------

namespace {

// Two meshes: "Body" (one triangle, one target "blink") and "Face" (a quad with interleaved
// positions, uint16 indices, a float, a sparse and a normalised-short target; plus a triangle
// with uint32 indices), targets named smile, frown, open.
GltfBuilder two_mesh_model() {
  GltfBuilder b;
  b.model.extensionsUsed.push_back("KHR_mesh_quantization");  // the normalised-short target
  // Body.
  const int body = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
  const int blink = b.vec3({0, 0, 0, 0, 0, 0, 0, 0, 2});
  b.add_mesh("Body", {triangles_primitive(body, -1, {blink})}, {"blink"});

  // Face primitive 0: positions interleaved with 4 padding bytes (byteStride 16).
  std::vector<float> interleaved = {0, 0, 1, -7, 1, 0, 1, -7, 1, 1, 1, -7, 0, 1, 1, -7};
  const int quad = b.accessor(b.view(interleaved, 16), TINYGLTF_COMPONENT_TYPE_FLOAT, 4, TINYGLTF_TYPE_VEC3);
  const int quad_indices = b.accessor(b.view(std::vector<uint16_t>{0, 1, 2, 0, 2, 3}),
                                      TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, 6, TINYGLTF_TYPE_SCALAR);
  const int smile0 = b.vec3({0.5f, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0});
  // Sparse: no buffer view (zeros) except element 2.
  const int frown0 = b.accessor(-1, TINYGLTF_COMPONENT_TYPE_FLOAT, 4, TINYGLTF_TYPE_VEC3);
  {
    tinygltf::Accessor& a = b.model.accessors[frown0];
    a.sparse.isSparse = true;
    a.sparse.count = 1;
    a.sparse.indices.bufferView = b.view(std::vector<uint8_t>{2});
    a.sparse.indices.byteOffset = 0;
    a.sparse.indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
    a.sparse.values.bufferView = b.view(std::vector<float>{0, -0.25f, 0});
    a.sparse.values.byteOffset = 0;
  }
  const int open0 = b.accessor(b.view(std::vector<int16_t>{0, 0, 32767, 0, 0, -32767, 0, 0, 0, 0, 0, 16384}),
                               TINYGLTF_COMPONENT_TYPE_SHORT, 4, TINYGLTF_TYPE_VEC3, true);
  // Face primitive 1: one triangle, uint32 indices.
  const int tri = b.vec3({2, 0, 1, 3, 0, 1, 2, 1, 1});
  const int tri_indices =
      b.accessor(b.view(std::vector<uint32_t>{0, 1, 2}), TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, 3, TINYGLTF_TYPE_SCALAR);
  const int smile1 = b.vec3({0, 0, 0, 1, 0, 0, 0, 0, 0});
  const int frown1 = b.vec3({0, 0, 0, 0, 0, 0, 0, -1, 0});
  const int open1 = b.vec3({0, 0, 0, 0, 0, 0, 0, 0, 0});
  b.add_mesh("Face",
             {triangles_primitive(quad, quad_indices, {smile0, frown0, open0}),
              triangles_primitive(tri, tri_indices, {smile1, frown1, open1})},
             {"smile", "frown", "open"});
  return b;
}

void check_face_rig(const Rig& rig) {
  CHECK(rig.units == "m");
  REQUIRE(rig.neutral.vertex_count() == 7);
  REQUIRE(rig.neutral.triangle_count() == 3);
  Positions neutral(7, 3);
  neutral << 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1, 2, 0, 1, 3, 0, 1, 2, 1, 1;
  CHECK(rig.neutral.vertices == neutral);
  CHECK(rig.neutral.triangles.row(1) == Eigen::RowVector3i(0, 2, 3));
  CHECK(rig.neutral.triangles.row(2) == Eigen::RowVector3i(4, 5, 6));  // merged: offset by the quad's 4 vertices
  REQUIRE(rig.controller_count() == 3);
  CHECK(rig.controllers[0].name == "smile");
  CHECK(rig.controllers[1].name == "frown");
  CHECK(rig.controllers[2].name == "open");
  CHECK(rig.controllers[0].offset(0, 0) == 0.5);
  CHECK(rig.controllers[0].offset(5, 0) == 1.0);
  CHECK(rig.controllers[0].offset.cwiseAbs().sum() == 1.5);
  CHECK(rig.controllers[1].offset(2, 1) == -0.25);  // the sparse element
  CHECK(rig.controllers[1].offset(6, 1) == -1.0);
  CHECK(rig.controllers[1].offset.cwiseAbs().sum() == 1.25);
  CHECK(rig.controllers[2].offset(0, 2) == 1.0);   // normalised short 32767
  CHECK(rig.controllers[2].offset(1, 2) == -1.0);  // -32767
  CHECK(rig.controllers[2].offset(3, 2) == Approx(16384.0 / 32767.0));
  for (const Controller& c : rig.controllers) CHECK((c.min == 0 && c.max == 1));
  const Positions p = rig.evaluate(Eigen::Vector3d(1, 0, 0.5));
  CHECK(p(0, 0) == 0.5);
  CHECK(p(5, 0) == 4.0);
  CHECK(p(0, 2) == 1.5);
}

}  // namespace

TEST_CASE("glTF and GLB rigs: morph targets become controllers", "[rig][gltf]") {
  const fs::path dir = test::scratch_dir("rig_gltf");
  GltfBuilder builder = two_mesh_model();
  for (const char* file : {"two.gltf", "two.glb"}) {
    CAPTURE(file);
    const std::string path = builder.write(dir / file);
    // Default: the mesh with the most morph targets ("Face", 3 against 1).
    const Rig face = load_rig(path);
    CHECK(face.name == "two");
    CHECK(face.source == path);
    check_face_rig(face);
    // By name.
    const Rig body = load_rig(path, "Body");
    REQUIRE(body.controller_count() == 1);
    CHECK(body.controllers[0].name == "blink");
    CHECK(body.neutral.vertex_count() == 3);
    CHECK(body.controllers[0].offset(2, 2) == 2.0);
    CHECK(load_rig_gltf(path, "Face").controller_count() == 3);
  }
}

TEST_CASE("glTF rigs: unnamed targets, shared vertex buffers, non-indexed primitives", "[rig][gltf]") {
  GltfBuilder b;
  const int position = b.vec3({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});
  const int t0 = b.vec3({0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0});
  const int t1 = b.vec3({0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 3});
  const int first =
      b.accessor(b.view(std::vector<uint8_t>{0, 1, 2}), TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, 3, TINYGLTF_TYPE_SCALAR);
  const int second =
      b.accessor(b.view(std::vector<uint8_t>{0, 2, 3}), TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, 3, TINYGLTF_TYPE_SCALAR);
  // Two primitives over one vertex buffer (two materials, say): the vertices are shared.
  b.add_mesh("", {triangles_primitive(position, first, {t0, t1}), triangles_primitive(position, second, {t0, t1})});
  const Rig rig = load_rig_gltf(b.write(test::scratch_dir("rig_gltf_shared") / "shared.gltf"));
  CHECK(rig.neutral.vertex_count() == 4);
  CHECK(rig.neutral.triangle_count() == 2);
  REQUIRE(rig.controller_count() == 2);
  CHECK(rig.controllers[0].name == "target_0");
  CHECK(rig.controllers[1].name == "target_1");
  CHECK(rig.controllers[1].offset(3, 2) == 3.0);
}

TEST_CASE("bad glTF rigs say what is wrong", "[rig][gltf][errors]") {
  const fs::path dir = test::scratch_dir("rig_gltf_errors");
  const std::string two = two_mesh_model().write(dir / "two.gltf");
  CHECK_THROWS_WITH(load_rig_gltf(two, "Head"),
                    Contains("two.gltf") && Contains("no mesh named \"Head\"") && Contains("\"Body\", \"Face\""));

  {  // No morph targets anywhere.
    GltfBuilder b;
    b.add_mesh("Plain", {triangles_primitive(b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0}), -1, {})});
    const std::string path = b.write(dir / "plain.glb");
    CHECK_THROWS_WITH(load_rig_gltf(path), Contains("plain.glb") && Contains("no mesh has morph targets"));
    CHECK_THROWS_WITH(load_rig_gltf(path, "Plain"), Contains("mesh \"Plain\" has no morph targets"));
  }
  {  // Triangle strips.
    GltfBuilder b;
    tinygltf::Primitive p =
        triangles_primitive(b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0}), -1, {b.vec3({0, 0, 1, 0, 0, 0, 0, 0, 0})});
    p.mode = TINYGLTF_MODE_TRIANGLE_STRIP;
    b.add_mesh("Strip", {p});
    CHECK_THROWS_WITH(load_rig_gltf(b.write(dir / "strip.gltf")), Contains("mesh \"Strip\" primitive 0") &&
                                                                      Contains("triangle strip") &&
                                                                      Contains("not supported"));
  }
  {  // Duplicate target names.
    GltfBuilder b;
    const int position = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const int t = b.vec3({0, 0, 1, 0, 0, 0, 0, 0, 0});
    b.add_mesh("Dup", {triangles_primitive(position, -1, {t, t})}, {"blink", "blink"});
    CHECK_THROWS_WITH(load_rig_gltf(b.write(dir / "dup.gltf")),
                      Contains("morph targets 0 and 1 are both named \"blink\""));
  }
  {  // targetNames of the wrong length.
    GltfBuilder b;
    const int position = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const int t = b.vec3({0, 0, 1, 0, 0, 0, 0, 0, 0});
    b.add_mesh("Names", {triangles_primitive(position, -1, {t, t})}, {"only"});
    CHECK_THROWS_WITH(load_rig_gltf(b.write(dir / "names.gltf")),
                      Contains("targetNames should list 2 names") && Contains("got 1"));
  }
  {  // An index beyond the primitive's vertices.
    GltfBuilder b;
    const int position = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const int indices = b.accessor(b.view(std::vector<uint16_t>{0, 1, 7}), TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, 3,
                                   TINYGLTF_TYPE_SCALAR);
    b.add_mesh("Bad", {triangles_primitive(position, indices, {b.vec3({0, 0, 1, 0, 0, 0, 0, 0, 0})})});
    CHECK_THROWS_WITH(load_rig_gltf(b.write(dir / "index.gltf")),
                      Contains("primitive 0 indices") && Contains("index 7") && Contains("3 vertices"));
  }
  {  // A morph target with fewer deltas than vertices.
    GltfBuilder b;
    const int position = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
    b.add_mesh("Short", {triangles_primitive(position, -1, {b.vec3({0, 0, 1})})});
    CHECK_THROWS_WITH(load_rig_gltf(b.write(dir / "short.gltf")),
                      Contains("morph target 0 has 1 POSITION deltas but the primitive has 3 vertices"));
  }
  CHECK_THROWS_WITH(load_rig_gltf(write_text(dir / "junk.gltf", "{ not json")),
                    Contains("junk.gltf") && Contains("cannot read glTF"));
  CHECK_THROWS_WITH(load_rig_gltf(write_text(dir / "junk.glb", "glTF????")),
                    Contains("junk.glb") && Contains("cannot read glTF"));
  CHECK_THROWS_WITH(load_rig_gltf((dir / "absent.gltf").string()),
                    Contains("absent.gltf") && Contains("file not found"));
}

namespace {

// One triangle (accessor 0: POSITION, buffer view 0) with one morph target (accessor 1, view 1)
// and uint16 indices (accessor 2, view 2), for the hostile cases below to break.
GltfBuilder triangle_model() {
  GltfBuilder b;
  const int position = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
  const int target = b.vec3({0, 0, 1, 0, 0, 0, 0, 0, 0});
  const int indices = b.accessor(b.view(std::vector<uint16_t>{0, 1, 2}), TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, 3,
                                 TINYGLTF_TYPE_SCALAR);
  b.add_mesh("Tri", {triangles_primitive(position, indices, {target})});
  return b;
}

// A sparse accessor over `count` elements: `rows` replaced by `values` (xyz each).
void make_sparse(GltfBuilder& b, int accessor, const std::vector<uint8_t>& rows, const std::vector<float>& values) {
  tinygltf::Accessor& a = b.model.accessors[accessor];
  a.sparse.isSparse = true;
  a.sparse.count = static_cast<int>(rows.size());
  a.sparse.indices.bufferView = b.view(rows);
  a.sparse.indices.byteOffset = 0;
  a.sparse.indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
  a.sparse.values.bufferView = b.view(values);
  a.sparse.values.byteOffset = 0;
}

}  // namespace

TEST_CASE("glTF accessors are checked against the spec and their buffers before allocating", "[rig][gltf][errors]") {
  const fs::path dir = test::scratch_dir("rig_gltf_accessors");
  struct Case {
    const char* name;
    std::function<void(GltfBuilder&)> change;
    std::vector<std::string> message;  // substrings
  };
  const std::string position = "mesh \"Tri\" primitive 0 POSITION (accessor 0): ";
  const std::string target = "mesh \"Tri\" primitive 0 morph target 0 POSITION (accessor 1): ";
  const std::string indices = "mesh \"Tri\" primitive 0 indices (accessor 2): ";
  const std::vector<Case> cases = {
      // Counts that made std::bad_alloc.
      {"count 2^31",
       [](GltfBuilder& b) { b.model.accessors[0].count = size_t{1} << 31; },
       {position + "count 2147483648 is more than 2147483647 elements"}},
      {"count 2^32 + 5",
       [](GltfBuilder& b) { b.model.accessors[0].count = (size_t{1} << 32) + 5; },
       {position + "count 4294967301 is more than 2147483647 elements"}},
      {"count past the view",
       [](GltfBuilder& b) { b.model.accessors[0].count = 2147483647; },
       {position + "2147483647 elements of 12 bytes, 12 bytes apart from byteOffset 0, reach past the end of buffer "
                   "view 0 (36 bytes)"}},
      {"target count 2^31",
       [](GltfBuilder& b) { b.model.accessors[1].count = size_t{1} << 31; },
       {target + "count 2147483648 is more than"}},
      {"target count 4",
       [](GltfBuilder& b) { b.model.accessors[1].count = 4; },
       {target + "4 elements of 12 bytes", "reach past the end of buffer view 1"}},
      {"sparse-only target with another count",
       [](GltfBuilder& b) {
         b.model.accessors[1].bufferView = -1;
         b.model.accessors[1].count = 1000000;
         make_sparse(b, 1, {0}, {0, 0, 1});
       },
       {"morph target 0 has 1000000 POSITION deltas but the primitive has 3 vertices"}},
      {"byteOffset past the view",
       [](GltfBuilder& b) { b.model.accessors[0].byteOffset = 12; },
       {position + "3 elements of 12 bytes, 12 bytes apart from byteOffset 12, reach past the end"}},
      {"misaligned byteOffset",
       [](GltfBuilder& b) { b.model.accessors[0].byteOffset = 2; },
       {position + "byteOffset 2 is not a multiple of the component size 4"}},
      {"stride below the element",
       [](GltfBuilder& b) { b.model.bufferViews[0].byteStride = 8; },
       {position + "buffer view 0 has byteStride 8; expected a multiple of 4 between the element size 12 and 252"}},
      {"stride past the view",
       [](GltfBuilder& b) { b.model.bufferViews[0].byteStride = 16; },
       {position + "3 elements of 12 bytes, 16 bytes apart"}},
      {"view past the buffer",
       [](GltfBuilder& b) { b.model.bufferViews[1].byteLength = 1u << 30; },
       {target + "buffer view 1 (byteOffset 36, byteLength 1073741824) reaches past the end of buffer 0"}},
      {"missing buffer view",
       [](GltfBuilder& b) { b.model.accessors[0].bufferView = 17; },
       {position + "buffer view 17 does not exist"}},
      {"position without data",
       [](GltfBuilder& b) { b.model.accessors[0].bufferView = -1; },
       {position + "no buffer view"}},
      // Types the spec does not allow.
      {"UNSIGNED_BYTE positions",
       [](GltfBuilder& b) {
         b.model.accessors[0].componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
         b.model.accessors[0].normalized = true;
       },
       {position + "components are UNSIGNED_BYTE; expected FLOAT (glTF 2.0; integer positions need the "
                   "KHR_mesh_quantization extension)"}},
      {"DOUBLE positions",
       [](GltfBuilder& b) { b.model.accessors[0].componentType = TINYGLTF_COMPONENT_TYPE_DOUBLE; },
       {position + "components are DOUBLE; expected FLOAT"}},
      {"VEC2 positions",
       [](GltfBuilder& b) { b.model.accessors[0].type = TINYGLTF_TYPE_VEC2; },
       {position + "expected VEC3 elements, got VEC2"}},
      {"SHORT target without quantization",
       [](GltfBuilder& b) { b.model.accessors[1].componentType = TINYGLTF_COMPONENT_TYPE_SHORT; },
       {target + "components are SHORT; expected FLOAT"}},
      {"UNSIGNED_SHORT target with quantization",
       [](GltfBuilder& b) {
         b.model.extensionsUsed.push_back("KHR_mesh_quantization");
         b.model.accessors[1].componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
       },
       {target + "components are UNSIGNED_SHORT; expected FLOAT, BYTE or SHORT (KHR_mesh_quantization)"}},
      {"normalized FLOAT",
       [](GltfBuilder& b) { b.model.accessors[1].normalized = true; },
       {target + "normalized is set, which glTF allows only for BYTE, UNSIGNED_BYTE, SHORT and UNSIGNED_SHORT"}},
      {"FLOAT indices",
       [](GltfBuilder& b) { b.model.accessors[2].componentType = TINYGLTF_COMPONENT_TYPE_FLOAT; },
       {indices + "components are FLOAT; expected UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT"}},
      {"signed indices",
       [](GltfBuilder& b) { b.model.accessors[2].componentType = TINYGLTF_COMPONENT_TYPE_SHORT; },
       {indices + "components are SHORT"}},
      {"VEC3 indices",
       [](GltfBuilder& b) { b.model.accessors[2].type = TINYGLTF_TYPE_VEC3; },
       {indices + "expected SCALAR elements, got VEC3"}},
      {"normalized indices",
       [](GltfBuilder& b) { b.model.accessors[2].normalized = true; },
       {indices + "normalized is set"}},
      {"index past the vertices",
       [](GltfBuilder& b) { reinterpret_cast<uint16_t*>(b.model.buffers[0].data.data() + 72)[2] = 3; },
       {indices + "index 3 (entry 2) is out of range (the primitive has 3 vertices)"}},
      {"Draco-compressed primitive",
       [](GltfBuilder& b) {
         b.model.extensionsRequired.push_back("KHR_draco_mesh_compression");
         b.model.meshes[0].primitives[0].extensions["KHR_draco_mesh_compression"] =
             tinygltf::Value(tinygltf::Value::Object{{"bufferView", tinygltf::Value(0)}});
       },
       {"mesh \"Tri\" primitive 0: Draco-compressed (KHR_draco_mesh_compression; POSITION is accessor 0) is not "
        "supported; re-export the avatar without mesh compression"}},
      // Values.
      {"nan position",
       [](GltfBuilder& b) { reinterpret_cast<float*>(b.model.buffers[0].data.data())[4] = NAN; },
       {position + "element 1 has a non-finite value (y = "}},
      {"infinite delta",
       [](GltfBuilder& b) { reinterpret_cast<float*>(b.model.buffers[0].data.data() + 36)[8] = INFINITY; },
       {target + "element 2 has a non-finite value (z = inf)"}},
      // Sparse storage.
      {"sparse index past the count",
       [](GltfBuilder& b) {
         make_sparse(b, 1, {5}, {0, 0, 1});
       },
       {target + "sparse index 5 (entry 0) is out of range (3 elements)"}},
      {"sparse indices not increasing",
       [](GltfBuilder& b) {
         make_sparse(b, 1, {2, 1}, {0, 0, 1, 0, 0, 2});
       },
       {target + "sparse indices must increase strictly; entry 1 is 1 after 2"}},
      {"sparse count past the accessor",
       [](GltfBuilder& b) {
         make_sparse(b, 1, {0}, {0, 0, 1});
         b.model.accessors[1].sparse.count = 4;
       },
       {target + "sparse count 4 is outside 1..3"}},
      {"sparse values past their view",
       [](GltfBuilder& b) {
         make_sparse(b, 1, {0, 1}, {0, 0, 1});
       },
       {"(accessor 1) sparse values: 2 elements of 12 bytes"}},
      {"sparse FLOAT indices",
       [](GltfBuilder& b) {
         make_sparse(b, 1, {0}, {0, 0, 1});
         b.model.accessors[1].sparse.indices.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
       },
       {target + "sparse indices are FLOAT"}},
      {"sparse nan",
       [](GltfBuilder& b) {
         make_sparse(b, 1, {1}, {0, NAN, 0});
       },
       {"(accessor 1) sparse values: element 0 has a non-finite value"}},
  };
  for (const Case& c : cases) {
    CAPTURE(c.name);
    GltfBuilder b = triangle_model();
    c.change(b);
    const std::string path = b.write(dir / "hostile.glb");
    try {
      load_rig_gltf(path);
      FAIL("no error thrown");
    } catch (const Error& e) {
      const std::string message = e.what();
      CAPTURE(message);
      CHECK_THAT(message, Contains(path));
      for (const std::string& part : c.message) CHECK_THAT(message, Contains(part));
    }
  }
}

TEST_CASE("glTF: a sparse count beyond 32 bits is named as the file writes it", "[rig][gltf]") {
  GltfBuilder b = triangle_model();
  make_sparse(b, 1, {0}, {0, 0, 1});
  b.model.accessors[1].sparse.count = 1234567;  // a marker, replaced in the text below
  const fs::path dir = test::scratch_dir("rig_gltf_sparse_count");
  const std::string written = b.write(dir / "marker.gltf");
  std::ifstream in(written, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t at = text.find("1234567");
  REQUIRE(at != std::string::npos);
  text.replace(at, 7, "2147483648");  // 2^31: tinygltf reads it into an int as -2^31
  const std::string path = write_text(dir / "huge.gltf", text);
  CHECK_THROWS_WITH(load_rig_gltf(path), Contains(path) && Contains("sparse count 2147483648 is outside 1..3"));
}

TEST_CASE("glTF: sparse morph targets over a buffer view, quantized positions", "[rig][gltf]") {
  GltfBuilder b = triangle_model();
  make_sparse(b, 1, {0, 2}, {0.5f, 0, 0, 0, -1, 0});  // replaces elements 0 and 2 of (0 0 1, 0 0 0, 0 0 0)
  // Quantized positions: normalised unsigned shorts under KHR_mesh_quantization.
  b.model.extensionsUsed.push_back("KHR_mesh_quantization");
  const int quantized =
      b.accessor(b.view(std::vector<uint16_t>{0, 0, 0, 7, 65535, 0, 0, 7, 0, 65535, 0, 7}, 8),
                 TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, 3, TINYGLTF_TYPE_VEC3, true);  // xyz + padding
  b.model.meshes[0].primitives[0].attributes["POSITION"] = quantized;
  const Rig rig = load_rig_gltf(b.write(test::scratch_dir("rig_gltf_sparse") / "sparse.glb"));
  REQUIRE(rig.neutral.vertex_count() == 3);
  CHECK(rig.neutral.vertices.row(1) == Eigen::RowVector3d(1, 0, 0));
  CHECK(rig.neutral.vertices.row(2) == Eigen::RowVector3d(0, 1, 0));
  CHECK(rig.controllers[0].offset.row(0) == Eigen::RowVector3d(0.5, 0, 0));
  CHECK(rig.controllers[0].offset.row(1) == Eigen::RowVector3d(0, 0, 0));
  CHECK(rig.controllers[0].offset.row(2) == Eigen::RowVector3d(0, -1, 0));
}

TEST_CASE("glTF: morph targets that would need gigabytes are refused", "[rig][gltf][errors]") {
  GltfBuilder b = triangle_model();
  std::vector<float> xyz(3 * 100000, 0.0f);
  xyz[3] = 1;
  xyz[7] = 1;
  const int position = b.vec3(xyz);
  const int delta = b.vec3(xyz);
  std::vector<int> targets(1000, delta);  // one accessor, 1000 targets: a small file, 2.2 GiB dense
  b.add_mesh("Many", {triangles_primitive(position, -1, targets)});
  b.model.meshes[1].primitives[0].indices =
      b.accessor(b.view(std::vector<uint32_t>{0, 1, 2}), TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, 3, TINYGLTF_TYPE_SCALAR);
  const std::string path = b.write(test::scratch_dir("rig_gltf_many") / "many.glb");
  CHECK_THROWS_WITH(load_rig_gltf(path, "Many"), Contains("many.glb") &&
                                                     Contains("1000 morph targets x 100000 vertices") &&
                                                     Contains("MiB of positions and offsets, more than 2048 MiB"));
}
