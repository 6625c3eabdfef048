// glTF avatars as artists ship them (geometry/rig.h, geometry/rig_parts.h): node transforms,
// several meshes as one avatar with eye/teeth parts, rig.yaml pointing at a glTF file.
#include <tiny_gltf.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/log.h"
#include "geometry/gltf_builder.h"
#include "geometry/metrics.h"
#include "geometry/rig.h"
#include "geometry/rig_parts.h"
#include "scratch.h"
#include "test_support.h"

using Catch::Contains;
using namespace retarget;

namespace rig_gltf_test {

namespace fs = std::filesystem;
using test::GltfBuilder;
using test::triangles_primitive;
using test::write_file;

int triangle_indices(GltfBuilder& b) {
  return b.accessor(b.view(std::vector<uint16_t>{0, 1, 2}), TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, 3,
                    TINYGLTF_TYPE_SCALAR);
}

// A Ready Player Me-like avatar, each mesh on a node of its own, all at the identity:
//   Head (4 vertices, a quad; targets jawOpen: vertex 0 down, smile: vertex 1 along x),
//   EyeLeft (x = +0.5) and EyeRight (x = -0.5), triangles; EyeLeft has a target lookUp the
//   head lacks; EyeLashLeft (not an eye); Wolf3D_Teeth (target jawOpen: every vertex down).
GltfBuilder avatar_model() {
  GltfBuilder b;
  const int quad = b.vec3({-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0});
  const int quad_indices = b.accessor(b.view(std::vector<uint16_t>{0, 1, 2, 0, 2, 3}),
                                      TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, 6, TINYGLTF_TYPE_SCALAR);
  const int jaw = b.vec3({0, -0.5f, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0});
  const int smile = b.vec3({0, 0, 0, 0.1f, 0, 0, 0, 0, 0, 0, 0, 0});
  b.add_mesh("Head", {triangles_primitive(quad, quad_indices, {jaw, smile})}, {"jawOpen", "smile"});
  auto triangle = [&b](float x, float y, float z) {
    return b.vec3({x - 0.1f, y - 0.1f, z, x + 0.1f, y - 0.1f, z, x, y + 0.1f, z});
  };
  const int look = b.vec3({0, 0.05f, 0, 0, 0.05f, 0, 0, 0.05f, 0});
  b.add_mesh("EyeLeft", {triangles_primitive(triangle(0.5f, 0.5f, 0.1f), triangle_indices(b), {look})}, {"lookUp"});
  b.add_mesh("EyeRight", {triangles_primitive(triangle(-0.5f, 0.5f, 0.1f), triangle_indices(b), {})});
  b.add_mesh("EyeLashLeft", {triangles_primitive(triangle(0.5f, 0.7f, 0.1f), triangle_indices(b), {})});
  const int teeth_down = b.vec3({0, -0.2f, 0, 0, -0.2f, 0, 0, -0.2f, 0});
  b.add_mesh("Wolf3D_Teeth", {triangles_primitive(triangle(0, -0.5f, 0.05f), triangle_indices(b), {teeth_down})},
             {"jawOpen"});
  return b;
}

// One triangle (0 0 0, 1 0 0, 0 1 0) with a target "t" moving vertex 1 by (1, 0, 0) and vertex
// 2 by (0, 0, 1); no nodes (the tests add them).
GltfBuilder triangle_only() {
  GltfBuilder b;
  const int position = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
  const int delta = b.vec3({0, 0, 0, 1, 0, 0, 0, 0, 1});
  b.add_mesh("Face", {triangles_primitive(position, triangle_indices(b), {delta})}, {"t"});
  b.model.nodes.clear();
  return b;
}

tinygltf::Node mesh_node(int mesh) {
  tinygltf::Node n;
  n.mesh = mesh;
  return n;
}

void set_scene(GltfBuilder& b, std::vector<int> roots) {
  tinygltf::Scene scene;
  scene.nodes = std::move(roots);
  b.model.scenes = {scene};
  b.model.defaultScene = 0;
}

const std::vector<int>& part_vertices(const Rig& rig, const std::string& name) {
  for (const RigPart& p : rig.parts)
    if (p.name == name) return p.vertices;
  FAIL("no part " << name);
  static const std::vector<int> none;
  return none;
}

const RigPart* find_part(const Rig& rig, const std::string& name) {
  for (const RigPart& p : rig.parts)
    if (p.name == name) return &p;
  return nullptr;
}

}  // namespace rig_gltf_test

using namespace rig_gltf_test;

TEST_CASE("glTF rigs: positions go through the node hierarchy, deltas through its linear part", "[rig][gltf]") {
  const fs::path dir = test::scratch_dir("rig_gltf_nodes");
  SECTION("translation x rotation x scale, parent and child") {
    GltfBuilder b = triangle_only();
    tinygltf::Node parent;
    parent.translation = {0, 1.5, 0};
    parent.scale = {2, 2, 2};
    parent.children = {1};
    tinygltf::Node child = mesh_node(0);
    child.rotation = {0, 0, std::sqrt(0.5), std::sqrt(0.5)};  // 90 degrees about +z
    b.model.nodes = {parent, child};
    set_scene(b, {0});
    const Rig rig = load_rig_gltf(b.write(dir / "trs.glb"));
    REQUIRE(rig.neutral.vertex_count() == 3);
    // x -> y, y -> -x, then x2, then up 1.5.
    CHECK(rig.neutral.vertices.row(0).isApprox(Eigen::RowVector3d(0, 1.5, 0)));
    CHECK(rig.neutral.vertices.row(1).isApprox(Eigen::RowVector3d(0, 3.5, 0)));
    CHECK(rig.neutral.vertices.row(2).isApprox(Eigen::RowVector3d(-2, 1.5, 0)));
    REQUIRE(rig.controller_count() == 1);
    CHECK(rig.controllers[0].offset.row(0).norm() == 0);
    CHECK(rig.controllers[0].offset.row(1).isApprox(Eigen::RowVector3d(0, 2, 0)));  // no translation
    CHECK(rig.controllers[0].offset.row(2).isApprox(Eigen::RowVector3d(0, 0, 2)));
    CHECK(rig.units == "m");
  }
  SECTION("a column-major matrix: centimetres to metres, moved to body height") {
    GltfBuilder b = triangle_only();
    tinygltf::Node node = mesh_node(0);
    node.matrix = {0.01, 0, 0, 0, 0, 0.01, 0, 0, 0, 0, 0.01, 0, 0.1, 1.6, 0.02, 1};
    b.model.nodes = {node};
    set_scene(b, {0});
    const Rig rig = load_rig_gltf(b.write(dir / "matrix.gltf"));
    CHECK(rig.neutral.vertices.row(1).isApprox(Eigen::RowVector3d(0.11, 1.6, 0.02)));
    CHECK(rig.controllers[0].offset.row(2).isApprox(Eigen::RowVector3d(0, 0, 0.01)));
  }
  SECTION("a mesh instanced twice is read at its first instance in the scene") {
    GltfBuilder b = triangle_only();
    tinygltf::Node first = mesh_node(0), second = mesh_node(0), group;
    first.translation = {5, 0, 0};
    second.translation = {9, 0, 0};
    group.children = {2, 1};  // depth-first: node 2 (x + 5) comes first
    b.model.nodes = {group, second, first};
    set_scene(b, {0});
    const Rig rig = load_rig_gltf(b.write(dir / "instanced.glb"));
    CHECK(rig.neutral.vertices.row(0).isApprox(Eigen::RowVector3d(5, 0, 0)));
  }
  SECTION("a node cycle ends; a mesh no scene node instances keeps its own coordinates") {
    GltfBuilder b = triangle_only();
    tinygltf::Node a, c = mesh_node(0);
    a.translation = {1, 0, 0};
    a.children = {1};
    c.children = {0};  // back to the parent: not entered again
    b.model.nodes = {a, c};
    set_scene(b, {0});
    CHECK(load_rig_gltf(b.write(dir / "cycle.glb")).neutral.vertices.row(0).isApprox(Eigen::RowVector3d(1, 0, 0)));
    tinygltf::Node empty;  // the scene holds only this node, which instances nothing
    empty.name = "Empty";
    b.model.nodes.push_back(empty);
    set_scene(b, {2});
    CHECK(load_rig_gltf(b.write(dir / "unplaced.glb")).neutral.vertices.row(0).norm() == 0);
  }
  SECTION("a skinned mesh: its node's world matrix, the skin not applied (the bind pose as stored)") {
    GltfBuilder b = triangle_only();
    tinygltf::Node skinned = mesh_node(0), joint;
    skinned.translation = {0, 1, 0};
    skinned.skin = 0;
    joint.name = "Head";
    joint.translation = {100, 0, 0};
    b.model.nodes = {skinned, joint};
    tinygltf::Skin skin;
    skin.joints = {1};
    b.model.skins = {skin};
    set_scene(b, {0, 1});
    const Rig rig = load_rig_gltf(b.write(dir / "skinned.glb"));
    CHECK(rig.neutral.vertices.row(1).isApprox(Eigen::RowVector3d(1, 1, 0)));
  }
  SECTION("bad transforms name the node") {
    GltfBuilder b = triangle_only();
    tinygltf::Node node = mesh_node(0);
    node.name = "Armature";
    node.rotation = {0, 0, 0, 0};
    b.model.nodes = {node};
    set_scene(b, {0});
    const std::string path = b.write(dir / "zero.glb");
    CHECK_THROWS_WITH(load_rig_gltf(path),
                      Contains(path) && Contains("node 0 \"Armature\": rotation is a zero quaternion"));
    b.model.nodes[0].rotation.clear();
    b.model.nodes[0].children = {7};
    CHECK_THROWS_WITH(load_rig_gltf(b.write(dir / "child.glb")),
                      Contains("node 0 \"Armature\" names node 7, which does not exist (1 nodes)"));
  }
}

TEST_CASE("glTF avatars of several meshes: eye, teeth and tongue meshes become parts and give the eyes",
          "[rig][gltf]") {
  const fs::path dir = test::scratch_dir("rig_gltf_parts");
  const std::string path = avatar_model().write(dir / "avatar.glb");
  const Rig rig = load_rig_gltf(path);  // the head: the most morph targets
  // Head 0-3, EyeLeft 4-6, EyeRight 7-9, Wolf3D_Teeth 10-12; EyeLashLeft is no part.
  CHECK(rig.gltf_meshes == std::vector<std::string>{"Head", "EyeLeft", "EyeRight", "Wolf3D_Teeth"});
  REQUIRE(rig.neutral.vertex_count() == 13);
  CHECK(rig.neutral.triangle_count() == 5);
  CHECK(rig.neutral.triangles.row(4) == Eigen::RowVector3i(10, 11, 12));
  REQUIRE(rig.parts.size() == 3);
  CHECK(rig.parts[0].name == "EyeLeft");
  CHECK(rig.parts[0].kind == PartKind::eye_left);
  CHECK(rig.parts[0].mesh == "EyeLeft");
  CHECK(rig.parts[0].vertices == std::vector<int>{4, 5, 6});
  CHECK(rig.parts[1].kind == PartKind::eye_right);
  CHECK(rig.parts[2].kind == PartKind::teeth);
  CHECK(rig.parts[2].vertices == std::vector<int>{10, 11, 12});
  CHECK(rig.eyes.left == std::vector<int>{4, 5, 6});
  CHECK(rig.eyes.right == std::vector<int>{7, 8, 9});
  CHECK(millimetres_per_unit(rig.neutral.vertices, rig.eyes) == Approx(100.0));  // eyes 1 unit apart

  // Targets matched by name: the teeth move with jawOpen, not with smile; lookUp is no controller.
  REQUIRE(rig.controller_count() == 2);
  CHECK(rig.controllers[0].name == "jawOpen");
  CHECK(rig.controllers[0].offset.row(0).isApprox(Eigen::RowVector3d(0, -0.5, 0)));
  CHECK((rig.controllers[0].offset.middleRows(10, 3).col(1) - Eigen::Vector3d::Constant(-0.2)).norm() < 1e-6);
  CHECK(rig.controllers[0].offset.middleRows(4, 6).norm() == 0);  // the eyes stay
  CHECK(rig.controllers[1].offset.bottomRows(9).norm() == 0);

  // Read back as recorded: exactly those meshes.
  const Rig again = load_rig(path, rig.gltf_meshes);
  CHECK(again.neutral.vertices == rig.neutral.vertices);
  CHECK(again.parts.size() == 3);
  // An explicit list: no parts found by name.
  GltfRigOptions head_only;
  head_only.meshes = {"Head"};
  head_only.find_parts = false;
  CHECK(load_rig_gltf(path, head_only).neutral.vertex_count() == 4);
  GltfRigOptions listed;
  listed.meshes = {"Head", "EyeLashLeft"};
  const Rig with_lashes = load_rig_gltf(path, listed);
  REQUIRE(with_lashes.parts.size() == 1);
  CHECK(with_lashes.parts[0].kind == PartKind::other);
  CHECK(with_lashes.eyes.left.empty());
  listed.meshes = {"Head", "Head"};
  CHECK_THROWS_WITH(load_rig_gltf(path, listed), Contains("mesh \"Head\" is named twice"));
  listed.meshes = {"EyeRight", "Head"};
  CHECK_THROWS_WITH(load_rig_gltf(path, listed),
                    Contains("mesh \"EyeRight\" has no morph targets (the first mesh of the list"));
  CHECK_THROWS_WITH(load_rig(path, std::vector<std::string>{"Head", "Nose"}),
                    Contains("no mesh named \"Nose\" (meshes: \"Head\", \"EyeLeft\""));
}

TEST_CASE("eye meshes whose names contradict their sides are kept as named, with a warning", "[rig][gltf]") {
  GltfBuilder b = avatar_model();
  std::swap(b.model.meshes[1].name, b.model.meshes[2].name);  // "EyeLeft" now at x = -0.5
  const std::string path = b.write(test::scratch_dir("rig_gltf_sides") / "mirrored.glb");
  std::vector<std::string> warnings;
  const log::Sink previous = log::set_sink([&](log::Level level, const std::string& message) {
    if (level == log::Level::warn) warnings.push_back(message);
  });
  const Rig rig = load_rig_gltf(path);
  log::set_sink(previous);
  CHECK(rig.eyes.left == std::vector<int>{7, 8, 9});  // the mesh named EyeLeft, appended second
  REQUIRE(warnings.size() == 1);
  CHECK_THAT(warnings[0], Contains("mirrored.glb: the left eye part's centre (x = -0.5) is at smaller x than the "
                                   "right one's (0.5)"));
}

TEST_CASE("part kinds from common mesh names", "[rig][gltf]") {
  struct Case {
    const char* name;
    std::optional<PartKind> kind;
  };
  const std::vector<Case> cases = {
      {"EyeLeft", PartKind::eye_left},
      {"EyeRight", PartKind::eye_right},
      {"eye_L", PartKind::eye_left},
      {"Eye.R", PartKind::eye_right},
      {"LeftEye", PartKind::eye_left},
      {"Eyeball_R", PartKind::eye_right},
      {"EyeL", PartKind::eye_left},
      {"EYE_RIGHT", PartKind::eye_right},
      {"Wolf3D_Teeth", PartKind::teeth},
      {"CC_Base_Teeth01", PartKind::teeth},
      {"Tongue", PartKind::tongue},
      {"Eyes", std::nullopt},
      {"EyeLashLeft", std::nullopt},
      {"Eyebrow_L", std::nullopt},
      {"CC_Base_EyeOcclusion_L", std::nullopt},
      {"Wolf3D_Head", std::nullopt},
      {"Body", std::nullopt},
      {"Eye_L_R", std::nullopt},
  };
  for (const Case& c : cases) {
    CAPTURE(c.name);
    CHECK(part_kind_from_name(c.name) == c.kind);
  }
  CHECK(name_words("Wolf3D_EyeLeft.001") == std::vector<std::string>{"wolf", "d", "eye", "left"});
}

TEST_CASE("rig.yaml pointing at a glTF file: landmarks, eyes and parts for a GLB avatar", "[rig][gltf]") {
  const fs::path dir = test::scratch_dir("rig_gltf_yaml");
  avatar_model().write(dir / "avatar.glb");
  SECTION("one mesh named; eye and teeth meshes found by name; a part by vertex ranges") {
    const std::string yaml = write_file(dir / "rig.yaml",
                                        "gltf: avatar.glb\n"
                                        "mesh: Head\n"
                                        "name: rpm\n"
                                        "landmarks: {chin: 0, brow: 3, eye_l: 4}\n"
                                        "parts:\n"
                                        "  lips: {vertices: [0, [1, 2]]}\n"
                                        "  tongue_tip: {vertices: [3]}\n");
    const Rig rig = load_rig(yaml);
    CHECK(rig.name == "rpm");
    CHECK(rig.units == "m");
    CHECK(rig.source == yaml);
    CHECK(rig.controller_count() == 2);
    CHECK(rig.neutral.vertex_count() == 13);
    CHECK(rig.landmarks == std::map<std::string, int>{{"chin", 0}, {"brow", 3}, {"eye_l", 4}});
    CHECK(rig.eyes.left == std::vector<int>{4, 5, 6});
    REQUIRE(rig.parts.size() == 5);
    const RigPart* lips = find_part(rig, "lips");
    REQUIRE(lips);
    CHECK(lips->kind == PartKind::other);
    CHECK(lips->vertices == std::vector<int>{0, 1, 2});
    CHECK(find_part(rig, "tongue_tip")->kind == PartKind::tongue);
    CHECK(find_part(rig, "Wolf3D_Teeth")->kind == PartKind::teeth);
  }
  SECTION("a list of meshes; parts naming meshes append them and set their kinds; eyes: wins") {
    const std::string yaml = write_file(dir / "rig.yaml",
                                        "gltf: avatar.glb\n"
                                        "meshes: [Head, Wolf3D_Teeth]\n"
                                        "units: cm\n"
                                        "parts:\n"
                                        "  eye_l: {mesh: EyeLeft}\n"
                                        "  eye_r: {mesh: EyeRight}\n"
                                        "  face: {mesh: Head}\n");
    const Rig rig = load_rig(yaml);
    CHECK(rig.units == "cm");
    CHECK(rig.gltf_meshes == std::vector<std::string>{"Head", "Wolf3D_Teeth", "EyeLeft", "EyeRight"});
    CHECK(part_vertices(rig, "Wolf3D_Teeth") == std::vector<int>{4, 5, 6});
    CHECK(part_vertices(rig, "eye_l") == std::vector<int>{7, 8, 9});
    CHECK(find_part(rig, "eye_l")->kind == PartKind::eye_left);
    CHECK(find_part(rig, "EyeLeft") == nullptr);  // renamed by the yaml
    CHECK(part_vertices(rig, "face") == std::vector<int>{0, 1, 2, 3});
    CHECK(rig.eyes.left == std::vector<int>{7, 8, 9});
    CHECK(rig.eyes.right == std::vector<int>{10, 11, 12});

    write_file(dir / "rig.yaml", "gltf: avatar.glb\nmesh: Head\neyes: {left: [0], right: [1]}\n");
    const Rig given = load_rig(yaml);
    CHECK(given.eyes.left == std::vector<int>{0});
    CHECK(given.parts.size() == 3);
  }
  SECTION("errors name rig.yaml and the key") {
    struct Case {
      std::string yaml;
      std::vector<std::string> message;
    };
    const std::vector<Case> cases = {
        {"gltf: avatar.glb\nneutral: n.obj\n", {"rig.yaml:2", "neutral", "not allowed with `gltf:`"}},
        {"gltf: avatar.glb\nmesh: Nose\n", {"rig.yaml:2", "mesh", "avatar.glb", "no mesh named \"Nose\""}},
        {"gltf: absent.glb\n", {"rig.yaml:1", "gltf", "file not found"}},
        {"gltf: avatar.glb\nmesh: Head\nmeshes: [Head]\n", {"meshes", "not both"}},
        {"gltf: avatar.glb\nparts: {x: {vertices: [13]}}\n", {"parts.x.vertices", "vertex 13 is out of range"}},
        {"gltf: avatar.glb\nparts: {x: {vertices: [[3, 1]]}}\n", {"first <= last"}},
        {"gltf: avatar.glb\nparts: {x: {mesh: Head, kind: eyeball}}\n",
         {"parts.x.kind", "expected eye_left, eye_right, teeth, tongue or other"}},
        {"gltf: avatar.glb\nparts: {x: {mesh: Head, vertices: [1]}}\n", {"exactly one of `mesh:` and `vertices:`"}},
        {"gltf: avatar.glb\nparts: {EyeLeft: {vertices: [1]}}\n", {"two parts are named \"EyeLeft\""}},
        {"gltf: avatar.glb\nparts: {x: {mesh: Nose}}\n", {"parts", "no mesh named \"Nose\""}},
        {"neutral: n.obj\nmesh: Head\n", {"mesh", "add `gltf: FILE`"}},
    };
    for (const Case& c : cases) {
      CAPTURE(c.yaml);
      const std::string yaml = write_file(dir / "rig.yaml", c.yaml);
      try {
        load_rig(yaml);
        FAIL("no error thrown");
      } catch (const Error& e) {
        const std::string message = e.what();
        CAPTURE(message);
        CHECK_THAT(message, Contains("rig.yaml"));
        for (const std::string& part : c.message) CHECK_THAT(message, Contains(part));
      }
    }
  }
}

TEST_CASE("write_rig_folder keeps a glTF avatar's parts as vertex ranges", "[rig][gltf]") {
  const fs::path dir = test::scratch_dir("rig_gltf_write");
  const Rig rig = load_rig_gltf(avatar_model().write(dir / "avatar.glb"));
  write_rig_folder((dir / "folder").string(), rig);
  const Rig back = load_rig((dir / "folder").string());
  REQUIRE(back.parts.size() == rig.parts.size());
  for (size_t k = 0; k < rig.parts.size(); ++k) {
    CHECK(back.parts[k].name == rig.parts[k].name);
    CHECK(back.parts[k].kind == rig.parts[k].kind);
    CHECK(back.parts[k].vertices == rig.parts[k].vertices);
  }
  CHECK(back.eyes.left == rig.eyes.left);
  CHECK(back.eyes.right == rig.eyes.right);
}

TEST_CASE("a file tinygltf cannot read because of meshopt says so", "[rig][gltf][errors]") {
  const fs::path dir = test::scratch_dir("rig_gltf_meshopt");
  // A meshopt fallback buffer without data in a .gltf: tinygltf refuses the file itself.
  const std::string path = write_file(dir / "meshopt.gltf",
                                      R"({"asset": {"version": "2.0"}, "extensionsUsed": ["EXT_meshopt_compression"],
          "extensionsRequired": ["EXT_meshopt_compression"],
          "buffers": [{"byteLength": 36, "extensions": {"EXT_meshopt_compression": {"fallback": true}}}],
          "meshes": [{"name": "Head", "primitives": [{"attributes": {"POSITION": 0}}]}]})");
  CHECK_THROWS_WITH(load_rig_gltf(path), Contains(path) && Contains("cannot read glTF") &&
                                             Contains("the file uses EXT_meshopt_compression (compressed geometry), "
                                                      "which is not supported; re-export"));
}

TEST_CASE("meshopt-compressed buffer views are refused by mesh, primitive and accessor", "[rig][gltf][errors]") {
  const fs::path dir = test::scratch_dir("rig_gltf_meshopt_view");
  // tinygltf does not write buffer views' extensions: the file is written by hand.
  const std::vector<float> data = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  std::ofstream(dir / "tri.bin", std::ios::binary)
      .write(reinterpret_cast<const char*>(data.data()), static_cast<std::streamsize>(data.size() * 4));
  const std::string body = R"("buffers": [{"uri": "tri.bin", "byteLength": 72}],
      "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36, "extensions": {"EXT_meshopt_compression":
                         {"buffer": 0, "byteLength": 36, "byteStride": 12, "count": 3, "mode": "ATTRIBUTES"}}},
                      {"buffer": 0, "byteOffset": 36, "byteLength": 36}],
      "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
                    {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"}],
      "meshes": [{"name": "Head", "primitives": [{"attributes": {"POSITION": 0}, "targets": [{"POSITION": 1}]}]}],
      "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0})";
  const std::string required = write_file(dir / "required.gltf", R"({"asset": {"version": "2.0"},
      "extensionsUsed": ["EXT_meshopt_compression"], "extensionsRequired": ["EXT_meshopt_compression"],)" +
                                                                     body);
  CHECK_THROWS_WITH(load_rig_gltf(required),
                    Contains(required) && Contains("mesh \"Head\" primitive 0 POSITION (accessor 0): buffer view 0 is "
                                                   "meshopt-compressed (EXT_meshopt_compression), which is not "
                                                   "supported; re-export the avatar without mesh compression"));
  // Only used: the view's own bytes are the uncompressed fallback.
  const std::string optional = write_file(
      dir / "optional.gltf", R"({"asset": {"version": "2.0"}, "extensionsUsed": ["EXT_meshopt_compression"],)" + body);
  const Rig rig = load_rig_gltf(optional);
  CHECK(rig.neutral.vertices.row(1) == Eigen::RowVector3d(1, 0, 0));
  CHECK(rig.controllers[0].offset.row(2) == Eigen::RowVector3d(0, 0, 1));
}
