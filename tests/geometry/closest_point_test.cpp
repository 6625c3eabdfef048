#include "geometry/closest_point.h"

#include <Eigen/Geometry>
#include <catch2/catch.hpp>

#include "core/random.h"
#include "test_support.h"

using namespace retarget;

namespace {

// The closest point by checking every triangle, optionally only those facing `direction`.
SurfacePoint brute_force(const Mesh& mesh, const Eigen::Vector3d& p, const Eigen::Vector3d* direction = nullptr,
                         double min_cosine = 0) {
  SurfacePoint best;
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.triangles(t, 0)), b = mesh.vertices.row(mesh.triangles(t, 1)),
                          c = mesh.vertices.row(mesh.triangles(t, 2));
    if (direction && (b - a).cross(c - a).normalized().dot(*direction) < min_cosine) continue;
    SurfacePoint s = closest_point_on_triangle(p, a, b, c);
    if (s.squared_distance < best.squared_distance) {
      s.triangle = t;
      best = s;
    }
  }
  return best;
}

}  // namespace

TEST_CASE("closest point on one triangle, every Voronoi region", "[closest_point]") {
  const Eigen::Vector3d a(0, 0, 0), b(2, 0, 0), c(0, 2, 0);
  struct Row {
    Eigen::Vector3d query, point, barycentric;
  };
  const Row table[] = {
      {{0.5, 0.5, 3}, {0.5, 0.5, 0}, {0.5, 0.25, 0.25}},  // face
      {{-1, -1, 1}, {0, 0, 0}, {1, 0, 0}},                // corner a
      {{3, -1, 0}, {2, 0, 0}, {0, 1, 0}},                 // corner b
      {{-1, 3, -2}, {0, 2, 0}, {0, 0, 1}},                // corner c
      {{1, -2, 0}, {1, 0, 0}, {0.5, 0.5, 0}},             // edge ab
      {{-2, 1, 0}, {0, 1, 0}, {0.5, 0, 0.5}},             // edge ac
      {{2, 2, 1}, {1, 1, 0}, {0, 0.5, 0.5}},              // edge bc
  };
  for (const Row& row : table) {
    const SurfacePoint s = closest_point_on_triangle(row.query, a, b, c);
    CHECK((s.point - row.point).norm() < 1e-14);
    CHECK((s.barycentric - row.barycentric).norm() < 1e-14);
    CHECK(s.squared_distance == Approx((row.query - row.point).squaredNorm()));
  }
}

TEST_CASE("closest point on a collapsed triangle is finite", "[closest_point]") {
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0), c(2, 0, 0);
  const SurfacePoint s = closest_point_on_triangle(Eigen::Vector3d(1.5, 1, 0), a, b, c);
  REQUIRE(s.point.allFinite());
  CHECK((s.point - Eigen::Vector3d(1.5, 0, 0)).norm() < 1e-14);
  CHECK(s.barycentric.sum() == Approx(1));
  const SurfacePoint p = closest_point_on_triangle(Eigen::Vector3d(1, 1, 1), a, a, a);
  CHECK((p.point - a).norm() == 0);
}

TEST_CASE("surface closest points agree with brute force, with and without a normal filter", "[closest_point]") {
  const Mesh sphere = test::uv_sphere(10, 14, 1.0);
  const ClosestSurfacePoint surface(sphere.vertices, sphere.triangles);
  Random random(7);
  for (int k = 0; k < 200; ++k) {
    const double x = random.uniform(-1.6, 1.6), y = random.uniform(-1.6, 1.6), z = random.uniform(-1.6, 1.6);
    const Eigen::Vector3d p(x, y, z);
    const SurfacePoint fast = surface.closest(p), slow = brute_force(sphere, p);
    REQUIRE(fast.found());
    CHECK(fast.squared_distance == Approx(slow.squared_distance).margin(1e-15));
    const Eigen::Vector3d corners = fast.barycentric;
    CHECK(corners.sum() == Approx(1));
    // A filter that only accepts triangles facing away from p's direction: on a sphere the
    // answer is on the far side.
    const Eigen::Vector3d direction = -p.normalized();
    const SurfacePoint fast_filtered = surface.closest(p, direction, 0.5);
    const SurfacePoint slow_filtered = brute_force(sphere, p, &direction, 0.5);
    REQUIRE(fast_filtered.found());
    // Ties (a closest point on a shared edge) may pick either triangle; both must qualify.
    CHECK(surface.triangle_normals().row(fast_filtered.triangle).dot(direction) >= 0.5);
    CHECK(fast_filtered.squared_distance == Approx(slow_filtered.squared_distance).margin(1e-15));
    CHECK(sphere.vertices.row(sphere.triangles(fast_filtered.triangle, 0)).dot(p) < 0.5);
  }
  // Nothing faces every direction at once: an impossible filter finds nothing.
  CHECK_FALSE(surface.closest(Eigen::Vector3d(0, 0, 2), Eigen::Vector3d(0, 0, 1), 1.1).found());
}

TEST_CASE("disabled triangles are never returned", "[closest_point]") {
  const Mesh grid = test::quad_grid(4, 4, 1.0, 1.0, [](double, double) { return 0.0; });
  std::vector<char> enabled(grid.triangle_count(), 1);
  enabled[0] = 0;
  const ClosestSurfacePoint surface(grid.vertices, grid.triangles, enabled);
  const Eigen::Vector3d inside_first =
      (grid.vertices.row(grid.triangles(0, 0)) + grid.vertices.row(grid.triangles(0, 1)) +
       grid.vertices.row(grid.triangles(0, 2))) /
      3.0;
  const SurfacePoint s = surface.closest(inside_first + Eigen::Vector3d(0, 0, 0.1));
  REQUIRE(s.found());
  CHECK(s.triangle != 0);
  CHECK(s.squared_distance > 0.01);
}

TEST_CASE("nearest points with a filter, a radius and a visit budget", "[closest_point]") {
  Random random(3);
  auto u = [&] { return random.uniform(0, 10); };
  Positions points(500, 3);
  for (int i = 0; i < points.rows(); ++i) points.row(i) << u(), u(), u();
  const NearestPoints search(points);
  auto even = [](int i) { return i % 2 == 0; };
  for (int k = 0; k < 50; ++k) {
    const double x = u(), y = u(), z = u();
    const Eigen::Vector3d q(x, y, z);
    int best = -1;
    double best_d2 = 1e300;
    for (int i = 0; i < points.rows(); i += 2) {
      const double d2 = (points.row(i).transpose() - q).squaredNorm();
      if (d2 < best_d2) best = i, best_d2 = d2;
    }
    CHECK(search.nearest(q, even) == best);
    CHECK(search.nearest(q, even, std::sqrt(best_d2) * 1.0001) == best);
    CHECK(search.nearest(q, even, std::sqrt(best_d2) * 0.9999) == -1);
  }
  // Only odd points exist among the first visit: a budget of one visit finds no even point
  // when the nearest point is odd.
  const Eigen::Vector3d at_odd = points.row(1);
  CHECK(search.nearest(at_odd, even, 1e9, 1) == -1);
  CHECK(search.nearest(
            at_odd, [](int) { return true; }, 1e9, 1) == 1);

  std::vector<char> enabled(points.rows(), 1);
  enabled[1] = 0;
  const NearestPoints without_one(points, enabled);
  CHECK(without_one.nearest(at_odd, [](int) { return true; }) != 1);
}
