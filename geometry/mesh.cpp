#include "geometry/mesh.h"

#include <cassert>
#include <utility>

namespace retarget {

void Polygons::add(const int* vertices, int count) {
  indices.insert(indices.end(), vertices, vertices + count);
  offsets.push_back(static_cast<int>(indices.size()));
}

void triangulate(Mesh& mesh) {
  const Polygons& faces = mesh.faces;
  int count = 0;
  for (int f = 0; f < faces.size(); ++f) count += std::max(0, faces.degree(f) - 2);
  mesh.triangles.resize(count, 3);
  mesh.triangle_face.resize(count);
  int t = 0;
  for (int f = 0; f < faces.size(); ++f) {
    const int* v = faces.begin(f);
    for (int k = 1; k + 1 < faces.degree(f); ++k, ++t) {
      mesh.triangles.row(t) << v[0], v[k], v[k + 1];
      mesh.triangle_face[t] = f;
    }
  }
}

Mesh mesh_from_triangles(Positions vertices, const Triangles& triangles, std::string source) {
  Mesh mesh;
  mesh.vertices = std::move(vertices);
  mesh.source = std::move(source);
  for (int t = 0; t < triangles.rows(); ++t) mesh.faces.add(triangles.row(t).data(), 3);
  triangulate(mesh);
  return mesh;
}

Mesh with_positions(const Mesh& topology, Positions vertices) {
  assert(vertices.rows() == topology.vertices.rows());
  Mesh mesh = topology;
  mesh.vertices = std::move(vertices);
  return mesh;
}

}  // namespace retarget
