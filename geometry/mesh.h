// A polygon mesh as the maths sees it (triangles) and as the user wrote it (polygons).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace retarget {

// #V x 3 vertex positions, row-major so a row is one vertex (x, y, z) in the
// mesh's own units (the ICT face uses cm).
using Positions = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
// #T x 3 vertex indices of triangles.
using Triangles = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;

// Faces as they stand in the file: polygon k has the vertex indices
// indices[offsets[k] .. offsets[k + 1]).
struct Polygons {
  std::vector<int> offsets{0};  // #faces + 1
  std::vector<int> indices;

  int size() const { return static_cast<int>(offsets.size()) - 1; }
  int degree(int face) const { return offsets[face + 1] - offsets[face]; }
  const int* begin(int face) const { return indices.data() + offsets[face]; }
  void add(const int* vertices, int count);
};

struct Mesh {
  Positions vertices;              // #V x 3
  Triangles triangles;             // #T x 3, fan triangulation of `faces`
  Polygons faces;                  // the file's own faces, written back unchanged
  std::vector<int> triangle_face;  // #T: the polygon each triangle came from
  std::string source;              // where the mesh came from, for error messages ("" if built in code)

  int vertex_count() const { return static_cast<int>(vertices.rows()); }
  int triangle_count() const { return static_cast<int>(triangles.rows()); }
};

// Fans every polygon from its first vertex. The split depends on connectivity
// only, so every mesh of one topology gets the same triangles.
// faces: polygons with at least 3 vertices; out: mesh.triangles, mesh.triangle_face.
void triangulate(Mesh& mesh);

// Builds a mesh from positions and triangles (each triangle is its own face).
Mesh mesh_from_triangles(Positions vertices, const Triangles& triangles, std::string source = "");

// Same connectivity as `topology`, new positions (#V x 3; must have topology's #V rows).
Mesh with_positions(const Mesh& topology, Positions vertices);

}  // namespace retarget
