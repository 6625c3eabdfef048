#include "synthetic/synthetic_faces.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "core/random.h"
#include "geometry/face_model.h"
#include "geometry/mesh_topology.h"
#include "geometry/metrics.h"
#include "geometry/rig.h"
#include "test_support.h"

using namespace retarget;
namespace fs = std::filesystem;

namespace {

const FaceModel& human() {
  static const FaceModel model = synthetic_human(1);
  return model;
}

const std::vector<SyntheticAvatar>& avatars() {
  static const std::vector<SyntheticAvatar> list = synthetic_avatars();
  return list;
}

const Blendshape& shape(const FaceModel& m, const std::string& name) {
  const int k = m.expression_index(name);
  REQUIRE(k >= 0);
  return m.expressions[k];
}

const Controller& controller(const Rig& rig, const std::string& name) {
  const int k = rig.controller_index(name);
  REQUIRE(k >= 0);
  return rig.controllers[k];
}

double distance(const Positions& V, int a, int b) { return (V.row(a) - V.row(b)).norm(); }

Eigen::RowVector3d centroid(const Positions& V, const std::vector<int>& set) {
  Eigen::RowVector3d c = Eigen::RowVector3d::Zero();
  for (int v : set) c += V.row(v);
  return c / static_cast<double>(set.size());
}

// Triangles whose normal turns by more than 90 degrees between `rest` and `moved`; the rest
// position of the first one goes to the log (a failing check names the place).
int flipped_triangles(const Mesh& mesh, const Positions& rest, const Positions& moved) {
  int count = 0;
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    const int a = mesh.triangles(t, 0), b = mesh.triangles(t, 1), c = mesh.triangles(t, 2);
    const Eigen::RowVector3d n0 = (rest.row(b) - rest.row(a)).cross(rest.row(c) - rest.row(a));
    const Eigen::RowVector3d n1 = (moved.row(b) - moved.row(a)).cross(moved.row(c) - moved.row(a));
    if (n0.dot(n1) <= 0 && count++ == 0)
      UNSCOPED_INFO("first flipped triangle at " << (rest.row(a) + rest.row(b) + rest.row(c)) / 3);
  }
  return count;
}

// Share of the displacement (sum of vertex offset lengths) on vertices with x > 0 at rest.
double left_share(const Positions& rest, const Positions& offset) {
  double left = 0, total = 0;
  for (int v = 0; v < rest.rows(); ++v) {
    const double d = offset.row(v).norm();
    total += d;
    if (rest(v, 0) > 0) left += d;
  }
  return total > 0 ? left / total : 0.0;
}

std::string file_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

std::map<std::string, std::string> folder_bytes(const fs::path& root) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(root))
    if (entry.is_regular_file()) files[fs::relative(entry.path(), root).string()] = file_bytes(entry.path());
  return files;
}

// Vertices of the connected parts (other than the largest, the skin) whose centroid lies within
// `radius` of an eye's landmark centre: the eyeball caps with their liners.
std::vector<int> eyeball_vertices(const Mesh& mesh, const EyeLandmarks& eyes, double radius) {
  const EdgeTopology topology = edge_topology(mesh.triangles);
  const Components parts = connected_components(topology, mesh.vertex_count());
  std::vector<int> size(parts.count(), 0);
  std::vector<Eigen::RowVector3d> sum(parts.count(), Eigen::RowVector3d::Zero());
  for (int v = 0; v < mesh.vertex_count(); ++v) {
    ++size[parts.component[v]];
    sum[parts.component[v]] += mesh.vertices.row(v);
  }
  const int skin = static_cast<int>(std::max_element(size.begin(), size.end()) - size.begin());
  std::vector<int> out;
  for (const auto* set : {&eyes.left, &eyes.right}) {
    const Eigen::RowVector3d eye = centroid(mesh.vertices, *set);
    for (int c = 0; c < parts.count(); ++c) {
      if (c == skin || (sum[c] / size[c] - eye).norm() > radius) continue;
      for (int v = 0; v < mesh.vertex_count(); ++v)
        if (parts.component[v] == c) out.push_back(v);
    }
  }
  return out;
}

// The largest amount by which any of `inner` lies in front of (+z) the skin covering it: the
// skin height at the vertex's (x, y), interpolated in the front-most forward-facing triangle
// (of the other vertices) that covers that point. Returns -1e9 if nothing is covered.
double poke_through(const Mesh& mesh, const Positions& V, const std::vector<int>& inner) {
  std::vector<bool> is_inner(V.rows(), false);
  for (int v : inner) is_inner[v] = true;
  double worst = -1e9;
  for (int v : inner) {
    const double px = V(v, 0), py = V(v, 1);
    double skin_z = -1e9;
    for (int t = 0; t < mesh.triangle_count(); ++t) {
      const int a = mesh.triangles(t, 0), b = mesh.triangles(t, 1), c = mesh.triangles(t, 2);
      if (is_inner[a] || is_inner[b] || is_inner[c]) continue;
      const double x0 = V(a, 0), y0 = V(a, 1), x1 = V(b, 0), y1 = V(b, 1), x2 = V(c, 0), y2 = V(c, 1);
      const double area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);  // > 0: faces +z
      if (area <= 1e-12) continue;
      const double w1 = ((px - x0) * (y2 - y0) - (x2 - x0) * (py - y0)) / area;
      const double w2 = ((x1 - x0) * (py - y0) - (px - x0) * (y1 - y0)) / area;
      if (w1 < 0 || w2 < 0 || w1 + w2 > 1) continue;
      skin_z = std::max(skin_z, (1 - w1 - w2) * V(a, 2) + w1 * V(b, 2) + w2 * V(c, 2));
    }
    if (skin_z > -1e9) worst = std::max(worst, V(v, 2) - skin_z);
  }
  return worst;
}

}  // namespace

TEST_CASE("the synthetic human has one topology of the required size, modes, names and landmarks", "[synthetic]") {
  const FaceModel& m = human();
  const int n = m.neutral.vertex_count();
  CHECK(n >= 3000);
  CHECK(n <= 12000);
  CHECK(m.units == "cm");
  CHECK(m.identities.size() >= 20);
  for (const Blendshape& b : m.identities) CHECK(b.offset.rows() == n);
  for (const Blendshape& b : m.expressions) CHECK(b.offset.rows() == n);
  CHECK(m.expressions.size() == synthetic_expression_names().size());
  for (const std::string& name : synthetic_expression_names()) CHECK(m.expression_index(name) >= 0);

  // Every blendshape the bundled default recipes use.
  const auto recipes =
      load_expression_recipes((fs::path(RETARGET_SOURCE_DIR) / "configs/expressions/facewarehouse47.yaml").string());
  CHECK(recipes.size() == 47);
  for (const ExpressionRecipe& recipe : recipes)
    for (const auto& [name, weight] : recipe.weights) {
      INFO(recipe.name << " uses " << name);
      CHECK(m.expression_index(name) >= 0);
    }
  CHECK_NOTHROW(m.expression(m.neutral.vertices, recipes.back().weights));

  // Landmarks: the advertised names, in range, left ones on +x.
  CHECK(m.landmarks.size() >= 35);
  CHECK(synthetic_landmark_names().size() == m.landmarks.size());
  for (const std::string& name : synthetic_landmark_names()) {
    INFO(name);
    REQUIRE(m.landmarks.count(name));
    const int v = m.landmarks.at(name);
    REQUIRE(v >= 0);
    REQUIRE(v < n);
    const double x = m.neutral.vertices(v, 0);
    if (name.size() > 5 && name.compare(name.size() - 5, 5, "_left") == 0) CHECK(x > 0.3);
    if (name.size() > 6 && name.compare(name.size() - 6, 6, "_right") == 0) CHECK(x < -0.3);
  }
  CHECK(m.neutral.vertices(m.landmarks.at("nose_tip"), 2) > m.neutral.vertices(m.landmarks.at("chin"), 2));

  // Proportions: eye centres ~6.2 cm apart, chin to forehead ~20 cm, frame +y up, +z front.
  REQUIRE_FALSE(m.eyes.left.empty());
  REQUIRE_FALSE(m.eyes.right.empty());
  const Eigen::RowVector3d left = centroid(m.neutral.vertices, m.eyes.left);
  const Eigen::RowVector3d right = centroid(m.neutral.vertices, m.eyes.right);
  CHECK((left - right).norm() == Approx(6.2).margin(0.6));
  CHECK(left.x() > 0);
  const double height =
      m.neutral.vertices(m.landmarks.at("forehead"), 1) - m.neutral.vertices(m.landmarks.at("chin_bottom"), 1);
  CHECK(height > 15.0);
  CHECK(height < 21.0);
  CHECK(m.neutral.vertices.col(1).maxCoeff() - m.neutral.vertices.col(1).minCoeff() == Approx(22).margin(3));
  CHECK(millimetres_per_unit(m.neutral.vertices, m.eyes) == Approx(100.0 / 6.2).epsilon(0.1));
}

TEST_CASE("the synthetic human is deterministic for a seed and differs between seeds", "[synthetic]") {
  const FaceModel a = synthetic_human(7), b = synthetic_human(7), c = synthetic_human(8);
  CHECK(a.neutral.vertices == b.neutral.vertices);
  for (size_t k = 0; k < a.identities.size(); ++k) CHECK(a.identities[k].offset == b.identities[k].offset);
  for (size_t k = 0; k < a.expressions.size(); ++k) CHECK(a.expressions[k].offset == b.expressions[k].offset);
  const double change = (a.neutral.vertices - c.neutral.vertices).rowwise().norm().maxCoeff();
  CHECK(change > 0.1);  // cm
  CHECK(change < 5.0);
  // Same topology and meaning for every seed.
  CHECK(a.neutral.faces.indices == c.neutral.faces.indices);
  CHECK(a.landmarks == c.landmarks);
}

TEST_CASE("identity modes change the shape without folding it", "[synthetic]") {
  const FaceModel& m = human();
  const Positions& rest = m.neutral.vertices;
  std::set<std::string> names;
  for (const Blendshape& mode : m.identities) {
    INFO(mode.name);
    names.insert(mode.name);
    CHECK(mode.offset.allFinite());
    const double largest = mode.offset.rowwise().norm().maxCoeff();
    CHECK(largest > 0.1);  // at least 1 mm somewhere
    CHECK(largest < 3.0);
    for (double c : {-2.5, 2.5}) CHECK(flipped_triangles(m.neutral, rest, rest + c * mode.offset) == 0);
  }
  CHECK(names.size() == m.identities.size());
  // People as the model means them: c ~ N(0, 1) in every mode at once.
  Random random(42);
  for (int person = 0; person < 20; ++person) {
    Eigen::VectorXd c(m.identities.size());
    for (int k = 0; k < c.size(); ++k) c(k) = random.normal();
    INFO("person " << person << ": |c| = " << c.norm());
    CHECK(flipped_triangles(m.neutral, rest, m.person(c)) == 0);
  }
}

TEST_CASE("expressions are smooth, finite and unfolded", "[synthetic]") {
  const FaceModel& m = human();
  for (const Blendshape& b : m.expressions) {
    INFO(b.name);
    CHECK(b.offset.allFinite());
    CHECK(b.offset.rowwise().norm().maxCoeff() > 0.1);
    CHECK(b.offset.rowwise().norm().maxCoeff() < 5.0);
    // mouthClose presses the lips together; like ARKit's it is meant on top of jawOpen.
    Positions moved = m.neutral.vertices + b.offset;
    if (b.name == "mouthClose") moved += shape(m, "jawOpen").offset;
    CHECK(flipped_triangles(m.neutral, m.neutral.vertices, moved) == 0);
  }
  // Every default recipe, on the mean face and on a few people.
  const auto recipes =
      load_expression_recipes((fs::path(RETARGET_SOURCE_DIR) / "configs/expressions/facewarehouse47.yaml").string());
  for (int person = 0; person < 3; ++person) {
    Eigen::VectorXd c = Eigen::VectorXd::Zero(m.identities.size());
    for (int k = 0; k < c.size(); ++k) c(k) = person * ((k * 7 + person) % 5 - 2) * 0.5;
    const Positions P = m.person(c);
    for (const ExpressionRecipe& recipe : recipes) {
      INFO("person " << person << ", " << recipe.name);
      CHECK(flipped_triangles(m.neutral, m.neutral.vertices, m.expression(P, recipe.weights)) == 0);
    }
  }
}

TEST_CASE("other seeds give unfolded models too", "[synthetic]") {
  for (uint64_t seed : {2, 5, 11, 12345}) {
    const FaceModel m = synthetic_human(seed);
    const Positions& rest = m.neutral.vertices;
    for (const Blendshape& mode : m.identities) {
      INFO("seed " << seed << ", " << mode.name);
      for (double c : {-2.5, 2.5}) CHECK(flipped_triangles(m.neutral, rest, rest + c * mode.offset) == 0);
    }
    for (const Blendshape& b : m.expressions) {
      INFO("seed " << seed << ", " << b.name);
      Positions moved = rest + b.offset;
      if (b.name == "mouthClose") moved += shape(m, "jawOpen").offset;
      CHECK(flipped_triangles(m.neutral, rest, moved) == 0);
    }
  }
}

TEST_CASE("eyeballs and their liners stay under the skin", "[synthetic]") {
  // With both eyes closed nothing of an eyeball or its liner may show: every such vertex lies
  // behind the skin in front of it.
  const FaceModel& m = human();
  const std::vector<int> balls = eyeball_vertices(m.neutral, m.eyes, 2.5);
  CHECK(balls.size() > 100);
  const Positions closed = m.expression(m.neutral.vertices, {{"eyeBlink_L", 1.0}, {"eyeBlink_R", 1.0}});
  CHECK(poke_through(m.neutral, closed, balls) < 0.0);
  for (const SyntheticAvatar& a : avatars()) {
    INFO(a.rig.name);
    const std::vector<int> parts = eyeball_vertices(a.rig.neutral, a.rig.eyes, 3.5);
    CHECK(parts.size() > 100);
    const Positions shut =
        a.rig.neutral.vertices + controller(a.rig, "blinkLeft").offset + controller(a.rig, "blinkRight").offset;
    CHECK(poke_through(a.rig.neutral, shut, parts) < 0.0);
  }
}

TEST_CASE("jawOpen parts the lips, mouthClose closes them again", "[synthetic]") {
  const FaceModel& m = human();
  const int upper = m.landmarks.at("lip_upper_center"), lower = m.landmarks.at("lip_lower_center");
  CHECK(distance(m.neutral.vertices, upper, lower) < 1e-9);  // closed at rest: the two rows coincide
  const Positions open = m.expression(m.neutral.vertices, {{"jawOpen", 1.0}});
  CHECK(distance(open, upper, lower) > 0.5);  // > 5 mm
  CHECK(open(lower, 1) < open(upper, 1) - 0.5);
  // The recipe jaw_open_lips_closed: lips meet again (within 1 mm).
  const Positions closed = m.expression(m.neutral.vertices, {{"jawOpen", 0.4}, {"mouthClose", 0.4}});
  CHECK(distance(closed, upper, lower) < 0.1);
  // The mouth corners stay joined (one shared vertex each).
  CHECK(m.landmarks.at("mouth_left") != m.landmarks.at("mouth_right"));
}

TEST_CASE("eyeBlink_L closes the left eye and leaves the right one", "[synthetic]") {
  const FaceModel& m = human();
  const Positions& rest = m.neutral.vertices;
  const Blendshape& blink = shape(m, "eyeBlink_L");
  const int up = m.landmarks.at("eyelid_upper_left"), low = m.landmarks.at("eyelid_lower_left");
  CHECK(distance(rest, up, low) > 0.7);  // open at rest
  const Positions closed = rest + blink.offset;
  CHECK(blink.offset(up, 1) < -0.5);       // the upper lid comes down
  CHECK(distance(closed, up, low) < 0.1);  // and meets the lower one
  for (int v : m.eyes.right) CHECK(blink.offset.row(v).norm() < 1e-9);
  CHECK(blink.offset.row(m.landmarks.at("eyelid_upper_right")).norm() < 1e-9);
  // The right blink mirrors it.
  const Blendshape& right = shape(m, "eyeBlink_R");
  CHECK(right.offset(m.landmarks.at("eyelid_upper_right"), 1) == Approx(blink.offset(up, 1)).margin(0.02));
}

TEST_CASE("_L shapes move the +x side, _R shapes mirror them", "[synthetic]") {
  const FaceModel& m = human();
  int pairs = 0;
  for (const Blendshape& b : m.expressions) {
    if (b.name.size() < 2 || b.name.compare(b.name.size() - 2, 2, "_L") != 0) continue;
    INFO(b.name);
    const Blendshape& r = shape(m, b.name.substr(0, b.name.size() - 2) + "_R");
    CHECK(left_share(m.neutral.vertices, b.offset) > 0.85);
    CHECK(left_share(m.neutral.vertices, r.offset) < 0.15);
    CHECK(r.offset.rowwise().norm().sum() == Approx(b.offset.rowwise().norm().sum()).epsilon(0.05));
    ++pairs;
  }
  CHECK(pairs == 16);
}

TEST_CASE("avatars have their own topologies, rigs, landmarks and correspondence tables", "[synthetic]") {
  const FaceModel& m = human();
  std::vector<std::string> shapes;
  for (const Blendshape& b : m.expressions) shapes.push_back(b.name);
  REQUIRE(avatars().size() >= 3);
  std::set<int> counts = {m.neutral.vertex_count()};
  std::set<std::string> names;
  for (const SyntheticAvatar& a : avatars()) {
    const Rig& rig = a.rig;
    INFO(rig.name);
    names.insert(rig.name);
    const int n = rig.neutral.vertex_count();
    CHECK(n >= 800);
    CHECK(n <= 5000);
    CHECK(counts.insert(n).second);  // its own topology
    CHECK(rig.controller_count() >= 12);
    CHECK(rig.controller_count() <= 40);
    CHECK(rig.units == "cm");
    CHECK_FALSE(a.description.empty());

    // Landmarks: in range, named like the human's, both sides where the feature exists.
    int shared = 0;
    for (const auto& [name, v] : rig.landmarks) {
      INFO(name);
      CHECK(v >= 0);
      CHECK(v < n);
      CHECK(m.landmarks.count(name));
      shared += m.landmarks.count(name) > 0;
      if (name.size() > 5 && name.compare(name.size() - 5, 5, "_left") == 0) {
        CHECK(rig.landmarks.count(name.substr(0, name.size() - 5) + "_right"));
        CHECK(rig.neutral.vertices(v, 0) > 0);
      }
    }
    CHECK(shared >= 15);
    for (const char* needed : {"eye_inner_left", "eye_outer_right", "mouth_left", "mouth_right", "lip_upper_center"})
      CHECK(rig.landmarks.count(needed));
    REQUIRE_FALSE(rig.eyes.left.empty());
    REQUIRE_FALSE(rig.eyes.right.empty());
    for (int v : rig.eyes.left) CHECK((v >= 0 && v < n));
    CHECK(centroid(rig.neutral.vertices, rig.eyes.left).x() > 0);

    // Controllers: unit ranges, non-trivial, finite, unfolded.
    std::vector<std::string> controllers;
    for (const Controller& c : rig.controllers) {
      INFO(c.name);
      controllers.push_back(c.name);
      CHECK(c.min == 0);
      CHECK(c.max == 1);
      CHECK(c.offset.rows() == n);
      CHECK(c.offset.allFinite());
      CHECK(c.offset.rowwise().norm().maxCoeff() > 0.1);
      CHECK(flipped_triangles(rig.neutral, rig.neutral.vertices, rig.neutral.vertices + c.offset) == 0);
      // A controller standing for left-side human shapes moves the avatar's left side.
      const auto& row = a.correspondence.at(c.name);
      bool left_only = !row.empty();
      for (const auto& entry : row)
        left_only &= entry.first.size() > 2 && entry.first.compare(entry.first.size() - 2, 2, "_L") == 0;
      if (left_only) CHECK(left_share(rig.neutral.vertices, c.offset) > 0.85);
    }

    // The table: a row per controller, only known names, most with a human counterpart, some
    // without, and no human shape in two rows (so it can be inverted).
    CHECK_NOTHROW(check_controller_correspondence(a.correspondence, controllers, shapes, rig.name));
    int with = 0, without = 0;
    std::map<std::string, int> uses;
    for (const auto& [c, row] : a.correspondence) {
      (row.empty() ? without : with) += 1;
      for (const auto& entry : row) ++uses[entry.first];
    }
    CHECK(with > rig.controller_count() / 2);
    CHECK(without >= 1);
    for (const auto& [human_shape, count] : uses) {
      INFO(human_shape);
      CHECK(count == 1);
    }

    // Blink and jaw mean what they say.
    const Controller& blink = controller(rig, "blinkLeft");
    const int up = rig.landmarks.at("eyelid_upper_left"), low = rig.landmarks.at("eyelid_lower_left");
    CHECK(distance(rig.neutral.vertices, up, low) > 0.7);
    CHECK(distance(rig.neutral.vertices + blink.offset, up, low) < 0.1);
    for (int v : rig.eyes.right) CHECK(blink.offset.row(v).norm() < 1e-9);
    const int jaw =
        rig.controller_index("jawOpen") >= 0 ? rig.controller_index("jawOpen") : rig.controller_index("mouthOpen");
    REQUIRE(jaw >= 0);
    const Positions open = rig.neutral.vertices + rig.controllers[jaw].offset;
    const int lip_up = rig.landmarks.at("lip_upper_center"), lip_low = rig.landmarks.at("lip_lower_center");
    CHECK(distance(rig.neutral.vertices, lip_up, lip_low) < 1e-9);
    CHECK(distance(open, lip_up, lip_low) > 0.5);
  }
  CHECK(names.size() == avatars().size());
}

TEST_CASE("correspondence tables map human recipes to controller weights", "[synthetic]") {
  const SyntheticAvatar& moppet = avatars().front();
  REQUIRE(moppet.rig.name == "moppet");
  auto weights = controller_weights_from_human(moppet.correspondence, {{"mouthSmile_L", 1.0}, {"mouthSmile_R", 1.0}});
  CHECK(weights.at("smileLeft") == Approx(1.0));
  CHECK(weights.at("smileRight") == Approx(1.0));
  CHECK(weights.at("blinkLeft") == Approx(0.0).margin(1e-9));
  CHECK(weights.at("headSquash") == 0.0);
  weights = controller_weights_from_human(moppet.correspondence, {{"browInnerUp_L", 1.0}});
  CHECK(weights.at("browUpLeft") == Approx(0.5));
  weights = controller_weights_from_human(moppet.correspondence, {{"jawOpen", 0.6}, {"eyeBlink_R", 2.0}});
  CHECK(weights.at("mouthOpen") == Approx(0.6));
  CHECK(weights.at("blinkRight") == 1.0);  // clamped to the range
}

TEST_CASE("the synthetic set round-trips through its files, byte for byte per seed", "[synthetic]") {
  const auto dir = test::scratch_dir("synthetic_set");
  const SyntheticSet set = synthetic_set(3);
  write_synthetic_set((dir / "a").string(), set);
  write_synthetic_set((dir / "b").string(), synthetic_set(3));
  const auto a = folder_bytes(dir / "a"), b = folder_bytes(dir / "b");
  CHECK(a.size() > 100);
  CHECK(a == b);
  CHECK(a.count("README.txt"));
  CHECK(a.count("human/face_model.yaml"));

  const FaceModel loaded = load_face_model((dir / "a/human/face_model.yaml").string());
  const FaceModel& h = set.human;
  CHECK(loaded.neutral.vertices == h.neutral.vertices);
  CHECK(loaded.neutral.faces.indices == h.neutral.faces.indices);
  REQUIRE(loaded.identities.size() == h.identities.size());
  REQUIRE(loaded.expressions.size() == h.expressions.size());
  for (size_t k = 0; k < h.expressions.size(); ++k) {
    CHECK(loaded.expressions[k].name == h.expressions[k].name);
    CHECK((loaded.expressions[k].offset - h.expressions[k].offset).cwiseAbs().maxCoeff() < 1e-12);
  }
  for (size_t k = 0; k < h.identities.size(); ++k)
    CHECK((loaded.identities[k].offset - h.identities[k].offset).cwiseAbs().maxCoeff() < 1e-12);
  CHECK(loaded.landmarks == h.landmarks);
  CHECK(loaded.eyes.left == h.eyes.left);
  CHECK(loaded.eyes.right == h.eyes.right);

  for (const SyntheticAvatar& avatar : set.avatars) {
    INFO(avatar.rig.name);
    const fs::path folder = dir / "a/avatars" / avatar.rig.name;
    const Rig rig = load_rig_folder(folder.string());
    CHECK(rig.name == avatar.rig.name);
    CHECK(rig.neutral.vertices == avatar.rig.neutral.vertices);
    REQUIRE(rig.controller_count() == avatar.rig.controller_count());
    for (int c = 0; c < rig.controller_count(); ++c) {
      CHECK(rig.controllers[c].name == avatar.rig.controllers[c].name);
      CHECK((rig.controllers[c].offset - avatar.rig.controllers[c].offset).cwiseAbs().maxCoeff() < 1e-12);
    }
    CHECK(rig.landmarks == avatar.rig.landmarks);
    CHECK(rig.eyes.left == avatar.rig.eyes.left);
    CHECK(load_controller_correspondence((folder / "correspondence.yaml").string()) == avatar.correspondence);
  }
  // Another seed writes another human.
  write_synthetic_set((dir / "c").string(), synthetic_set(4));
  CHECK(file_bytes(dir / "c/human/neutral.obj") != file_bytes(dir / "a/human/neutral.obj"));
  CHECK(file_bytes(dir / "c/avatars/fox/neutral.obj") == file_bytes(dir / "a/avatars/fox/neutral.obj"));
}
