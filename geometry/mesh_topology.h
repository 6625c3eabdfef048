// Connectivity derived from a mesh's triangles, computed once per topology.
#pragma once

#include <array>
#include <vector>

#include "geometry/mesh.h"

namespace retarget {

// Compressed rows: the items of row r are items[start[r] .. start[r + 1]).
struct CompressedRows {
  std::vector<int> start{0};
  std::vector<int> items;
  int rows() const { return static_cast<int>(start.size()) - 1; }
  int size(int r) const { return start[r + 1] - start[r]; }
};

// Undirected edges of the triangulation, each once with i < j, together with the
// vertices opposite the edge in its triangles (1 on a boundary, 2 inside, more where
// the mesh is non-manifold).
struct EdgeTopology {
  std::vector<std::array<int, 2>> edges;  // #E, (i, j) with i < j
  CompressedRows opposite;                // #E rows of opposite vertex indices
};

EdgeTopology edge_topology(const Triangles& triangles);

// Per-vertex lists (#V rows).
CompressedRows vertex_neighbors(const EdgeTopology& topology, int vertex_count);
CompressedRows vertex_triangles(const Triangles& triangles, int vertex_count);

// component[v] in [0, #components) for every vertex, numbered in order of each
// component's lowest vertex index; isolated vertices form their own components.
struct Components {
  std::vector<int> component;     // #V
  std::vector<int> first_vertex;  // #components: the lowest vertex index in each
  int count() const { return static_cast<int>(first_vertex.size()); }
};
Components connected_components(const EdgeTopology& topology, int vertex_count);

}  // namespace retarget
