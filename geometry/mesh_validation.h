// Checks a mesh before the maths sees it: what would break the pipeline throws, what it
// can live with (degenerate triangles, boundaries) is counted for the caller to log.
#pragma once

#include "geometry/mesh.h"

namespace retarget {

// A triangle is degenerate when it repeats a vertex index or its area is below this
// fraction of the squared bounding-box diagonal. Relative, so the test does not depend
// on the mesh's units (cm, m, mm).
constexpr double kDegenerateAreaRatio = 1e-12;

// Counts over the mesh's polygons (`faces`) and fan triangles (`triangles`).
// Edges are the polygons' own edges, not the fan diagonals.
struct MeshReport {
  int vertex_count = 0;
  int face_count = 0;                // polygons, as in the file
  int triangle_count = 0;            // after fan triangulation
  int degenerate_triangles = 0;      // repeated index or area < kDegenerateAreaRatio * diag^2
  int degenerate_faces = 0;          // polygons with at least one degenerate triangle
  int first_degenerate_face = -1;    // 0-based, -1 when there is none; for the log
  int unreferenced_vertices = 0;     // in no face; they have no neighbours for the Laplacian
  int edge_count = 0;                // distinct undirected polygon edges
  int boundary_edges = 0;            // used by one face
  int nonmanifold_edges = 0;         // used by three or more faces
  int inconsistent_edges = 0;        // used by two faces that run it the same way (a flipped face)
  double bounding_box_diagonal = 0;  // mesh units
};

// Throws retarget::Error naming mesh.source (or "mesh" when it is empty) for what no later
// step can work with: no vertices, no faces, a NaN/Inf coordinate (vertex index and
// coordinate), a face with fewer than 3 vertices, a face index outside [0, #V) (face number,
// index, #V). Indices in messages count from 0. read_mesh() and write_mesh() call it.
void require_valid_mesh(const Mesh& mesh);

// require_valid_mesh(), then counts what the maths tolerates (degenerate triangles,
// boundaries, non-manifold edges, ...) for the caller to log. Cost O(#V + #F), about a
// third of reading the mesh from OBJ. mesh.triangles must be triangulate()'s output.
MeshReport validate_mesh(const Mesh& mesh);

// Throws retarget::Error when `mesh` does not have the topology of `rest`: a different vertex
// count (names both counts and both sources), a different face count, or the first face
// whose vertex indices differ (face number and both index lists).
void require_same_topology(const Mesh& rest, const Mesh& mesh);

}  // namespace retarget
