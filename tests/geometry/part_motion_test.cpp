// Parts that move: a sheet of skin with a separate ball (the "teeth") that the jaw controller
// carries along and turns, rebuilt from DR features with and without the part motion.
#include "geometry/part_motion.h"

#include <Eigen/Geometry>
#include <catch2/catch.hpp>

#include "geometry/dr_features.h"
#include "geometry/primitive_meshes.h"
#include "geometry/reconstruction.h"
#include "scratch.h"

namespace retarget {
namespace part_motion_test {

using Catch::Matchers::Contains;
using test::error_of;

// Skin: a gently domed 1 x 1 sheet; part: a ball of radius 0.08 in front of its lower half.
// jaw: the skin below y = 0.5 drops smoothly, the ball drops 0.2 and turns 20 degrees about x;
// smile: a bump on the skin's upper half that leaves the ball alone.
Rig skin_and_ball() {
  const Mesh skin = quad_grid(16, 16, 1.0, 1.0, [](double x, double y) { return 0.2 * x * (1 - x) + 0.1 * y; });
  Mesh ball = uv_sphere(6, 10, 0.08);
  ball.vertices.rowwise() += Eigen::RowVector3d(0.5, 0.3, 0.25);
  const int n_skin = skin.vertex_count(), n = n_skin + ball.vertex_count();
  Positions V(n, 3);
  V << skin.vertices, ball.vertices;
  Triangles T(skin.triangle_count() + ball.triangle_count(), 3);
  T << skin.triangles, (ball.triangles.array() + n_skin).matrix();
  Rig rig;
  rig.name = "skin_and_ball";
  rig.neutral = mesh_from_triangles(V, T, "skin_and_ball");
  Controller jaw{"jaw", Positions::Zero(n, 3)}, smile{"smile", Positions::Zero(n, 3)};
  for (int v = 0; v < n_skin; ++v) {
    const double y = V(v, 1);
    if (y < 0.5) jaw.offset(v, 1) = -0.2 * (0.5 - y) / 0.5;
    smile.offset(v, 2) = 0.05 * std::exp(-((V(v, 0) - 0.5) * (V(v, 0) - 0.5) + (y - 0.8) * (y - 0.8)) / 0.02);
  }
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.35, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Vector3d centre(0.5, 0.3, 0.25);
  for (int v = n_skin; v < n; ++v) {
    const Eigen::Vector3d p = V.row(v).transpose();
    jaw.offset.row(v) = (turn * (p - centre) + centre + Eigen::Vector3d(0, -0.2, 0) - p).transpose();
  }
  rig.controllers = {jaw, smile};
  return rig;
}

std::vector<int> ball_vertices(const Rig& rig) {
  std::vector<int> v;
  for (int i = 17 * 17; i < rig.neutral.vertex_count(); ++i) v.push_back(i);
  return v;
}

double part_error(const Positions& a, const Positions& b, const std::vector<int>& part) {
  double worst = 0;
  for (int v : part) worst = std::max(worst, (a.row(v) - b.row(v)).norm());
  return worst;
}

// The rig at jaw 1 (smile 0), rebuilt from its DR features as the bundle rebuilds avatars (the
// sheet's top row, the still region, held at rest), without and with the part motion.
struct Rebuilt {
  Positions truth, still, moved;
};
Rebuilt rebuilt_at_jaw_open(const Rig& rig) {
  Eigen::VectorXd w(2);
  w << 1.0, 0.0;
  Rebuilt r;
  r.truth = rig.evaluate(w);
  const DrFeatureMatrix features = DrFeatures(rig.neutral).compute(r.truth);
  ReconstructionOptions options;
  for (int v = 16 * 17; v < 17 * 17; ++v) options.anchors.push_back(v);
  r.still = Reconstruction(rig.neutral, options).reconstruct(features);
  options.parts = std::make_shared<const PartMotion>(rig);
  r.moved = Reconstruction(rig.neutral, options).reconstruct(features);
  return r;
}

TEST_CASE("the separate pieces of a rig are its parts; rig.parts, when given, are used as they are",
          "[geometry][parts]") {
  Rig rig = skin_and_ball();
  const std::vector<std::vector<int>> found = rig_parts_to_move(rig);
  REQUIRE(found.size() == 1);
  CHECK(found[0] == ball_vertices(rig));
  // A named part on the skin is kept as it is; the unnamed ball still moves.
  rig.parts = {RigPart{"teeth", PartKind::teeth, "", {0, 1, 2, 3}}};
  CHECK(rig_parts_to_move(rig) == std::vector<std::vector<int>>{{0, 1, 2, 3}, ball_vertices(rig)});
  // Pieces of fewer than 3 vertices cannot be fitted rigidly: left out.
  rig.parts = {RigPart{"speck", PartKind::other, "", {0, 1}}};
  CHECK(rig_parts_to_move(rig) == std::vector<std::vector<int>>{ball_vertices(rig)});
  rig.parts = {RigPart{"Teeth", PartKind::teeth, "", {0, 1, 99999}}};
  CHECK_THAT(error_of([&] { rig_parts_to_move(rig); }), Contains("part \"Teeth\"") && Contains("vertex 99999"));
}

// skin_and_ball with a second ball above the first (the upper teeth, still) named with it as
// one part, as one mesh holds both rows of teeth in many exports, and the skin's lower half a
// separate island (as a texture seam leaves it) that the jaw carries down.
Rig two_rows_and_an_island() {
  const Rig base = skin_and_ball();
  Mesh upper = uv_sphere(6, 10, 0.08);
  upper.vertices.rowwise() += Eigen::RowVector3d(0.5, 0.5, 0.25);
  const int n0 = base.neutral.vertex_count(), n = n0 + upper.vertex_count();
  Positions V(n, 3);
  V << base.neutral.vertices, upper.vertices;
  // The sheet's quads below y = 0.5 keep their vertices; those above take no vertex of rows
  // 0..7: the triangles touching row 8 from below are dropped, so rows 0..7 are an island.
  std::vector<Eigen::RowVector3i> kept;
  for (Eigen::Index t = 0; t < base.neutral.triangles.rows(); ++t) {
    const Eigen::RowVector3i tri = base.neutral.triangles.row(t);
    int below = 0, at8 = 0;
    for (int k = 0; k < 3; ++k) {
      const int v = tri(k);
      if (v < 17 * 17) below += v / 17 < 8, at8 += v / 17 == 8;
    }
    if (!(below > 0 && at8 > 0)) kept.push_back(tri);
  }
  Triangles T(static_cast<Eigen::Index>(kept.size()) + upper.triangle_count(), 3);
  for (size_t i = 0; i < kept.size(); ++i) T.row(static_cast<Eigen::Index>(i)) = kept[i];
  T.bottomRows(upper.triangle_count()) = (upper.triangles.array() + n0).matrix();
  Rig rig;
  rig.name = "two_rows_and_an_island";
  rig.neutral = mesh_from_triangles(V, T, rig.name);
  for (const Controller& c : base.controllers) {
    Controller grown{c.name, Positions::Zero(n, 3)};
    grown.offset.topRows(n0) = c.offset;
    rig.controllers.push_back(grown);
  }
  std::vector<int> teeth = ball_vertices(base);
  for (int v = n0; v < n; ++v) teeth.push_back(v);
  rig.parts = {RigPart{"Teeth", PartKind::teeth, "Teeth", teeth}};
  return rig;
}

TEST_CASE("a named part of two pieces moves piece by piece, and a second island of skin is placed",
          "[geometry][parts]") {
  const Rig rig = two_rows_and_an_island();
  const std::vector<std::vector<int>> parts = rig_parts_to_move(rig);
  REQUIRE(parts.size() == 3);  // the lower row, the upper row, the island
  const std::vector<int>& teeth = rig.parts[0].vertices;
  const size_t row = teeth.size() / 2;  // both rows are the same sphere
  CHECK(parts[0] == std::vector<int>(teeth.begin(), teeth.begin() + static_cast<long>(row)));
  CHECK(parts[1] == std::vector<int>(teeth.begin() + static_cast<long>(row), teeth.end()));
  std::vector<int> island;
  for (int v = 0; v < 8 * 17; ++v) island.push_back(v);
  CHECK(parts[2] == island);
  const auto [truth, still, moved] = rebuilt_at_jaw_open(rig);
  for (const std::vector<int>& part : parts) {
    INFO("part of " << part.size() << " vertices from " << part.front() << ": at rest "
                    << part_error(still, truth, part) << ", moved " << part_error(moved, truth, part));
    CHECK(part_error(moved, truth, part) < 0.02);
  }
  CHECK(part_error(still, truth, parts[0]) > 0.1);  // the lower row, left at its rest centroid
  CHECK(part_error(still, truth, island) > 0.05);   // the island too
}

TEST_CASE("a part left at rest is moved and turned where the rig puts it for the skin around it", "[geometry][parts]") {
  const Rig rig = skin_and_ball();
  const PartMotion motion(rig);
  const std::vector<int> ball = ball_vertices(rig);
  // At jaw 1 the rig's ball is exactly turned and moved (between 0 and 1 a blendshape rig blends
  // the offsets linearly, which a rigid motion follows only approximately).
  Eigen::VectorXd w(2);
  w << 1.0, 0.5;
  const Positions truth = rig.evaluate(w);
  // Where reconstruction leaves it: turned as its features say, at its rest centroid.
  Positions mesh = truth;
  Eigen::RowVector3d rest_centroid = Eigen::RowVector3d::Zero(), centroid = Eigen::RowVector3d::Zero();
  for (int v : ball) {
    rest_centroid += rig.neutral.vertices.row(v);
    centroid += truth.row(v);
  }
  for (int v : ball) mesh.row(v) += (rest_centroid - centroid) / static_cast<double>(ball.size());
  REQUIRE(part_error(mesh, truth, ball) > 0.15);
  const Positions skin_before = mesh;
  motion.apply(mesh);
  CHECK(part_error(mesh, truth, ball) < 1e-6);
  for (int v = 0; v < 17 * 17; ++v) REQUIRE(mesh.row(v) == skin_before.row(v));
}

TEST_CASE("rebuilt from DR features, the part follows the jaw only with the part motion", "[geometry][parts]") {
  const Rig rig = skin_and_ball();
  const std::vector<int> ball = ball_vertices(rig);
  const auto [truth, still, moved] = rebuilt_at_jaw_open(rig);
  INFO("ball error at rest " << part_error(still, truth, ball) << ", moved " << part_error(moved, truth, ball));
  CHECK(part_error(still, truth, ball) > 0.1);
  CHECK(part_error(moved, truth, ball) < 0.01);
}

TEST_CASE("rebuilt from DR features, a part the skin does not show turns as its own shape says", "[geometry][parts]") {
  // look: the ball turns 25 degrees about y in place, the skin does not move (an eyeball's look,
  // an ear's swing): only the part's own shape tells the fit that it turned.
  Rig rig = skin_and_ball();
  const std::vector<int> ball = ball_vertices(rig);
  const int n = rig.neutral.vertex_count();
  Controller look{"look", Positions::Zero(n, 3)};
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.45, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Vector3d centre(0.5, 0.3, 0.25);
  for (int v : ball) {
    const Eigen::Vector3d p = rig.neutral.vertices.row(v).transpose();
    look.offset.row(v) = (turn * (p - centre) + centre - p).transpose();
  }
  rig.controllers.push_back(look);
  Eigen::VectorXd w(3);
  w << 0.0, 0.0, 1.0;
  const Positions truth = rig.evaluate(w);
  const DrFeatureMatrix features = DrFeatures(rig.neutral).compute(truth);
  ReconstructionOptions options;
  for (int v = 16 * 17; v < 17 * 17; ++v) options.anchors.push_back(v);
  options.parts = std::make_shared<const PartMotion>(rig);
  const Positions moved = Reconstruction(rig.neutral, options).reconstruct(features);
  // Left where the rig puts it for a still skin (look 0), the ball would be off by its turn.
  double unturned = 0;
  for (int v : ball) unturned = std::max(unturned, (rig.neutral.vertices.row(v) - truth.row(v)).norm());
  INFO("ball error " << part_error(moved, truth, ball) << ", unturned " << unturned);
  REQUIRE(unturned > 0.025);
  CHECK(part_error(moved, truth, ball) < 0.1 * unturned);
}

TEST_CASE("bad parts are refused with the part and the vertex named", "[geometry][parts]") {
  const Rig rig = skin_and_ball();
  CHECK_THAT(error_of([&] { PartMotion(rig, {{0, 1, 100000}}); }), Contains("part 0") && Contains("100000"));
  CHECK_THAT(error_of([&] { PartMotion(rig, {{0, 1, 2}, {2, 3, 4}}); }), Contains("vertex 2 is in two parts"));
  std::vector<int> all(static_cast<size_t>(rig.neutral.vertex_count()));
  for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  CHECK_THAT(error_of([&] { PartMotion(rig, {all}); }), Contains("no skin"));
  Positions wrong(3, 3);
  CHECK_THAT(error_of([&] { PartMotion(rig).apply(wrong); }), Contains("3 vertices"));
}

}  // namespace part_motion_test
}  // namespace retarget
