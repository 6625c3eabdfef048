#include "geometry/mesh_validation.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/error.h"
#include "geometry/metrics.h"

namespace retarget {

namespace {

std::string name_of(const Mesh& mesh) { return mesh.source.empty() ? "mesh" : mesh.source; }

// 11248 -> "11,248": vertex counts of face meshes are read at a glance this way.
std::string grouped(long long n) {
  std::string digits = std::to_string(n < 0 ? -n : n);
  std::string out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return n < 0 ? "-" + out : out;
}

std::string face_indices(const Polygons& faces, int f) {
  std::string out = "(";
  for (int k = 0; k < faces.degree(f); ++k) out += (k ? " " : "") + std::to_string(faces.begin(f)[k]);
  return out + ")";
}

}  // namespace

void require_valid_mesh(const Mesh& mesh) {
  const int nv = mesh.vertex_count();
  const Polygons& faces = mesh.faces;
  if (nv == 0) throw Error(name_of(mesh), "the mesh has no vertices");
  if (faces.size() == 0) throw Error(name_of(mesh), "the mesh has no faces (a point cloud is not a mesh)");

  const double* p = mesh.vertices.data();
  for (int i = 0; i < nv * 3; ++i)
    if (!std::isfinite(p[i]))
      throw Error(name_of(mesh), fmt::format("vertex {} has a non-finite coordinate ({} = {}); vertices count from 0",
                                             i / 3, "xyz"[i % 3], p[i]));

  for (int f = 0; f < faces.size(); ++f) {
    if (faces.degree(f) < 3)
      throw Error(name_of(mesh), fmt::format("face {} has {} vertices; a face needs at least 3 (faces count from 0)", f,
                                             faces.degree(f)));
    for (int k = 0; k < faces.degree(f); ++k) {
      const int v = faces.begin(f)[k];
      if (v < 0 || v >= nv)
        throw Error(name_of(mesh),
                    fmt::format("face {} refers to vertex {}, but the mesh has {} vertices (indices count from 0)", f,
                                v, grouped(nv)));
    }
  }
}

namespace {

// Edges bucketed by their lower vertex (a counting sort): linear time and no hashing.
void count_edges(const Mesh& mesh, MeshReport& report) {
  const Polygons& faces = mesh.faces;
  const int nv = mesh.vertex_count();
  std::vector<int> start(nv + 1, 0);
  for (int f = 0; f < faces.size(); ++f) {
    const int* v = faces.begin(f);
    const int n = faces.degree(f);
    for (int k = 0, prev = v[n - 1]; k < n; prev = v[k++])
      if (prev != v[k]) ++start[std::min(prev, v[k]) + 1];
  }
  for (int i = 0; i < nv; ++i) start[i + 1] += start[i];
  // Entry: the higher vertex shifted left, the direction in bit 0 (1 = runs high -> low).
  // Indices are below 2^31, so the entry fits 32 unsigned bits.
  std::vector<std::uint32_t> entries(start[nv]);
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (int f = 0; f < faces.size(); ++f) {
    const int* v = faces.begin(f);
    const int n = faces.degree(f);
    for (int k = 0, prev = v[n - 1]; k < n; prev = v[k++]) {
      const int a = prev, b = v[k];
      if (a == b) continue;
      entries[fill[std::min(a, b)]++] = (static_cast<std::uint32_t>(std::max(a, b)) << 1) | (a > b ? 1u : 0u);
    }
  }
  for (int i = 0; i < nv; ++i) {
    const std::uint32_t* first = entries.data() + start[i];
    const std::uint32_t* last = entries.data() + start[i + 1];
    // A vertex has a handful of higher neighbours: compare pairs rather than sort.
    for (const std::uint32_t* e = first; e != last; ++e) {
      const std::uint32_t key = *e >> 1;
      bool seen = false;
      for (const std::uint32_t* q = first; q != e && !seen; ++q) seen = (*q >> 1) == key;
      if (seen) continue;  // counted with its first occurrence
      int uses = 1;
      bool same_direction = false;
      for (const std::uint32_t* q = e + 1; q != last; ++q)
        if ((*q >> 1) == key) {
          ++uses;
          same_direction = (*q & 1u) == (*e & 1u);
        }
      ++report.edge_count;
      if (uses == 1) ++report.boundary_edges;
      if (uses > 2) ++report.nonmanifold_edges;
      if (uses == 2 && same_direction) ++report.inconsistent_edges;
    }
  }
}

}  // namespace

MeshReport validate_mesh(const Mesh& mesh) {
  require_valid_mesh(mesh);
  const Polygons& faces = mesh.faces;
  MeshReport report;
  report.vertex_count = mesh.vertex_count();
  report.face_count = faces.size();
  report.triangle_count = mesh.triangle_count();
  assert(static_cast<size_t>(mesh.triangle_count()) == faces.indices.size() - 2 * faces.size() &&
         mesh.triangle_face.size() == static_cast<size_t>(mesh.triangle_count()) &&
         "mesh.triangles is stale: call triangulate(mesh) after changing faces");

  std::vector<char> used(report.vertex_count, 0);
  for (int v : faces.indices) used[v] = 1;
  report.unreferenced_vertices = static_cast<int>(std::count(used.begin(), used.end(), 0));

  report.bounding_box_diagonal = bounding_box_diagonal(mesh.vertices);
  // |cross| = 2 * area; compare squares to skip the square root.
  const double twice_min_area = 2 * kDegenerateAreaRatio * report.bounding_box_diagonal * report.bounding_box_diagonal;
  const double threshold = twice_min_area * twice_min_area;
  int last_face = -1;
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    const int a = mesh.triangles(t, 0), b = mesh.triangles(t, 1), c = mesh.triangles(t, 2);
    bool degenerate = a == b || b == c || a == c;
    if (!degenerate) {
      const Eigen::Vector3d pa = mesh.vertices.row(a), pb = mesh.vertices.row(b), pc = mesh.vertices.row(c);
      degenerate = (pb - pa).cross(pc - pa).squaredNorm() <= threshold;
    }
    if (!degenerate) continue;
    ++report.degenerate_triangles;
    const int f = mesh.triangle_face[t];
    if (f != last_face) {
      ++report.degenerate_faces;
      if (report.first_degenerate_face < 0) report.first_degenerate_face = f;
      last_face = f;
    }
  }

  count_edges(mesh, report);
  return report;
}

void require_same_topology(const Mesh& rest, const Mesh& mesh) {
  const std::string name = mesh.source.empty() ? "the mesh" : mesh.source;
  const std::string rest_name = rest.source.empty() ? "the rest mesh" : "the rest mesh " + rest.source;
  if (mesh.vertex_count() != rest.vertex_count())
    throw Error(fmt::format("{} has {} vertices but {} has {}; all meshes must share one topology", name,
                            grouped(mesh.vertex_count()), rest_name, grouped(rest.vertex_count())));
  if (mesh.faces.size() != rest.faces.size())
    throw Error(fmt::format("{} has {} faces but {} has {}; all meshes must share one topology", name,
                            grouped(mesh.faces.size()), rest_name, grouped(rest.faces.size())));
  if (mesh.faces.offsets == rest.faces.offsets && mesh.faces.indices == rest.faces.indices) return;
  for (int f = 0; f < mesh.faces.size(); ++f) {
    const bool same = mesh.faces.degree(f) == rest.faces.degree(f) &&
                      std::equal(mesh.faces.begin(f), mesh.faces.begin(f) + mesh.faces.degree(f), rest.faces.begin(f));
    if (!same)
      throw Error(
          fmt::format("{}: face {} is {} but in {} it is {} (faces and vertices count from 0); all meshes "
                      "must share one topology, with the same vertex order",
                      name, f, face_indices(mesh.faces, f), rest_name, face_indices(rest.faces, f)));
  }
}

}  // namespace retarget
