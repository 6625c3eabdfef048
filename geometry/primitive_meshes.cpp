#include "geometry/primitive_meshes.h"

#include <cmath>

namespace retarget {

Mesh quad_grid(int nx, int ny, double sx, double sy, const std::function<double(double, double)>& height) {
  Mesh mesh;
  mesh.vertices.resize((nx + 1) * (ny + 1), 3);
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const double x = sx * i / nx, y = sy * j / ny;
      mesh.vertices.row(j * (nx + 1) + i) << x, y, height ? height(x, y) : 0.0;
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

Mesh uv_sphere(int rings, int segments, double r) {
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

Mesh tube(int rings, int segments, double r, double h) {
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

}  // namespace retarget
