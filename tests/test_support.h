// Shared helpers for the tests: small meshes built inline and a scratch folder.
// Tests never depend on the working directory or on ../shared/data.
#pragma once

#include <cmath>
#include <filesystem>
#include <string>

#include "geometry/mesh.h"

namespace retarget::test {

// A fresh, empty scratch folder below the build tree, unique per name.
inline std::filesystem::path scratch_dir(const std::string& name) {
  std::filesystem::path dir = std::filesystem::path(RETARGET_TEST_TMP) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// A (nx+1) x (ny+1) grid of quads over [0, sx] x [0, sy], z = height(x, y).
// Faces are quads (kept as polygons, fan-triangulated), so the mesh has a boundary.
template <typename Height>
Mesh quad_grid(int nx, int ny, double sx, double sy, Height height) {
  Mesh mesh;
  mesh.vertices.resize((nx + 1) * (ny + 1), 3);
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const double x = sx * i / nx, y = sy * j / ny;
      mesh.vertices.row(j * (nx + 1) + i) << x, y, height(x, y);
    }
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i;
      const int quad[4] = {a, a + 1, a + nx + 2, a + nx + 1};
      mesh.faces.add(quad, 4);
    }
  triangulate(mesh);
  return mesh;
}

// A curved open patch (a spherical cap-like bump over a quad grid), a stand-in for a face.
inline Mesh bumpy_patch(int n = 24) {
  return quad_grid(n, n, 2.0, 2.0, [](double x, double y) {
    const double dx = x - 1.0, dy = y - 1.0;
    return 0.6 * std::exp(-(dx * dx + dy * dy)) + 0.05 * std::sin(3 * x) * std::cos(2 * y);
  });
}

// A closed UV sphere of radius r with `rings` latitude bands and `segments` longitudes
// (triangles at the poles, quads elsewhere).
inline Mesh uv_sphere(int rings, int segments, double r = 1.0) {
  Mesh mesh;
  const int nv = 2 + (rings - 1) * segments;
  mesh.vertices.resize(nv, 3);
  mesh.vertices.row(0) << 0, 0, r;
  for (int i = 1; i < rings; ++i) {
    const double theta = M_PI * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double phi = 2 * M_PI * j / segments;
      mesh.vertices.row(1 + (i - 1) * segments + j) << r * std::sin(theta) * std::cos(phi),
          r * std::sin(theta) * std::sin(phi), r * std::cos(theta);
    }
  }
  mesh.vertices.row(nv - 1) << 0, 0, -r;
  auto ring = [&](int i, int j) { return 1 + (i - 1) * segments + (j % segments); };
  for (int j = 0; j < segments; ++j) {
    const int top[3] = {0, ring(1, j), ring(1, j + 1)};
    mesh.faces.add(top, 3);
  }
  for (int i = 1; i + 1 < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const int quad[4] = {ring(i, j), ring(i + 1, j), ring(i + 1, j + 1), ring(i, j + 1)};
      mesh.faces.add(quad, 4);
    }
  for (int j = 0; j < segments; ++j) {
    const int bottom[3] = {ring(rings - 1, j), nv - 1, ring(rings - 1, j + 1)};
    mesh.faces.add(bottom, 3);
  }
  triangulate(mesh);
  return mesh;
}

// An open tube along z: radius r, length h, `rings` x `segments` quads (two boundary loops).
inline Mesh tube(int rings, int segments, double r = 0.5, double h = 2.0) {
  Mesh mesh;
  mesh.vertices.resize((rings + 1) * segments, 3);
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double phi = 2 * M_PI * j / segments;
      mesh.vertices.row(i * segments + j) << r * std::cos(phi), r * std::sin(phi), h * i / rings;
    }
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const int a = i * segments + j, b = i * segments + (j + 1) % segments;
      const int quad[4] = {a, b, b + segments, a + segments};
      mesh.faces.add(quad, 4);
    }
  triangulate(mesh);
  return mesh;
}

}  // namespace retarget::test
