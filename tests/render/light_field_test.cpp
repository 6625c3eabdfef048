#include "render/light_field.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "core/error.h"
#include "geometry/primitive_meshes.h"

using namespace retarget;

namespace {

// A size x size mask: pixels whose centre satisfies inside(x, y) (pixel units, y down).
template <typename Inside>
std::vector<uint8_t> mask_of(int size, Inside inside) {
  std::vector<uint8_t> mask(static_cast<size_t>(size) * size);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) mask[static_cast<size_t>(y) * size + x] = inside(x + 0.5, y + 0.5);
  return mask;
}

// The mask turned a quarter turn: pixel (x, y) goes to (size - 1 - y, x).
std::vector<uint8_t> quarter_turn(const std::vector<uint8_t>& mask, int size) {
  std::vector<uint8_t> out(mask.size());
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x)
      out[static_cast<size_t>(x) * size + (size - 1 - y)] = mask[static_cast<size_t>(y) * size + x];
  return out;
}

}  // namespace

TEST_CASE("light field: a disk's moments and outline have no angular part", "[render][light_field]") {
  LightFieldOptions o;
  const int n = 64;
  const Eigen::VectorXf d =
      silhouette_descriptor(mask_of(n, [](double x, double y) { return std::hypot(x - 32, y - 32) < 25; }), n, n, o);
  REQUIRE(d.size() == light_field_view_size(o));
  REQUIRE(d.size() == 36 + 10);
  CHECK(d[0] == Approx(1));  // |Z_00| / |Z_00|
  // Order (n, m) runs n = 0..10, m = n % 2 .. n step 2: every m > 0 term vanishes on a disk.
  int i = 0;
  for (int order = 0; order <= o.zernike_order; ++order)
    for (int m = order % 2; m <= order; m += 2, ++i)
      if (m > 0) CHECK(d[i] < 0.02);
  // Its outline is a circle: the centroid distance is the same at every angle.
  for (int j = 0; j < o.fourier; ++j) CHECK(d[36 + j] < 0.02);
}

TEST_CASE("light field: a silhouette's descriptor ignores its rotation, position and size", "[render][light_field]") {
  LightFieldOptions o;
  const int n = 96;
  // An L shape, off centre.
  auto l_shape = [](double cx, double cy, double s) {
    return [=](double x, double y) {
      const double u = (x - cx) / s, v = (y - cy) / s;
      return (u >= 0 && u < 3 && v >= 0 && v < 1) || (u >= 0 && u < 1 && v >= 0 && v < 4);
    };
  };
  const Eigen::VectorXf a = silhouette_descriptor(mask_of(n, l_shape(10, 12, 10)), n, n, o);
  const Eigen::VectorXf turned = silhouette_descriptor(quarter_turn(mask_of(n, l_shape(10, 12, 10)), n), n, n, o);
  const Eigen::VectorXf moved = silhouette_descriptor(mask_of(n, l_shape(40, 30, 10)), n, n, o);
  const Eigen::VectorXf smaller = silhouette_descriptor(mask_of(n, l_shape(20, 20, 5)), n, n, o);
  const Eigen::VectorXf larger = silhouette_descriptor(mask_of(n, l_shape(10, 10, 20)), n, n, o);
  const Eigen::VectorXf disk =
      silhouette_descriptor(mask_of(n, [](double x, double y) { return std::hypot(x - 48, y - 48) < 30; }), n, n, o);
  CHECK(light_field_distance(a, moved) < 1e-5);
  CHECK(light_field_distance(a, turned) < 0.05 * light_field_distance(a, disk));
  CHECK(light_field_distance(a, smaller) < 0.25 * light_field_distance(a, disk));
  CHECK(light_field_distance(a, larger) < 0.25 * light_field_distance(a, disk));
  // An empty silhouette describes as zeros.
  CHECK(silhouette_descriptor(std::vector<uint8_t>(16 * 16, 0), 16, 16, o).isZero());
}

TEST_CASE("light field: meshes compare by shape, not by position or size", "[render][light_field]") {
  LightFieldOptions o;
  o.size = 48;
  const Mesh sphere = uv_sphere(16, 24);
  const Eigen::VectorXf d = light_field_descriptor(sphere, sphere.vertices, o);
  REQUIRE(d.size() == light_field_size(o));
  REQUIRE(d.size() == 10 * 46);
  Positions moved = sphere.vertices * 3.0;
  moved.col(0).array() += 5;
  CHECK(light_field_distance(d, light_field_descriptor(sphere, moved, o)) < 1e-3 * d.cwiseAbs().sum());
  // Squashed along y a little, and a lot: farther and farther from the sphere.
  Positions slightly = sphere.vertices, much = sphere.vertices;
  slightly.col(1) *= 0.8;
  much.col(1) *= 0.3;
  const double near = light_field_distance(d, light_field_descriptor(sphere, slightly, o));
  const double far = light_field_distance(d, light_field_descriptor(sphere, much, o));
  CHECK(near > 0);
  CHECK(far > 2 * near);
  // The silhouettes themselves: the sphere is a disk from every view (its area pi R^2, R the
  // farthest covered pixel from their centroid).
  for (int view = 0; view < 10; ++view) {
    const std::vector<uint8_t> mask = light_field_silhouette(sphere, sphere.vertices, view, o);
    double area = 0, cx = 0, cy = 0, radius = 0;
    for (int i = 0; i < o.size * o.size; ++i)
      if (mask[static_cast<size_t>(i)]) area += 1, cx += i % o.size + 0.5, cy += i / o.size + 0.5;
    REQUIRE(area > 100);
    cx /= area, cy /= area;
    for (int i = 0; i < o.size * o.size; ++i)
      if (mask[static_cast<size_t>(i)])
        radius = std::max(radius, std::hypot(i % o.size + 0.5 - cx, i / o.size + 0.5 - cy));
    CHECK(area / (M_PI * (radius + 0.5) * (radius + 0.5)) == Approx(1).epsilon(0.12));
  }
}

TEST_CASE("light field: bad options and inputs are refused naming what is wrong", "[render][light_field]") {
  LightFieldOptions o;
  o.size = 8;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("light_field.size"));
  o = {};
  o.zernike_order = 0;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("light_field.zernike_order"));
  o = {};
  o.fourier = 32;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("light_field.fourier"));
  const Mesh sphere = uv_sphere(4, 6);
  CHECK_THROWS_WITH(light_field_silhouette(sphere, sphere.vertices, 10), Catch::Contains("view 10"));
  CHECK_THROWS_WITH(light_field_distance(Eigen::VectorXf::Zero(3), Eigen::VectorXf::Zero(4)),
                    Catch::Contains("3 and 4"));
  CHECK_THROWS_AS(silhouette_descriptor(std::vector<uint8_t>(10), 4, 4), Error);
}
