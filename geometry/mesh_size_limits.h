// How large a mesh the commands that do dense per-vertex work take by default, checked right after
// the mesh is read and before any work: `retarget avatar init` (a 1M-vertex mesh took 53 s and
// 9 GB before its first message) and `retarget dataset` (every sample is a #V x 3 mesh and the
// VAE's input). Stylised heads are 2k-30k vertices, a scanned head up to ~100k.
#pragma once

#include <cstdint>
#include <string>

#include "geometry/mesh.h"

namespace retarget {

struct MeshSizeLimits {
  int64_t max_vertices = 200000;  // --max-vertices; >= 1
  int64_t max_faces = 400000;     // --max-faces (polygons as written); >= 1

  // Throws retarget::Error naming --max-vertices / --max-faces for a value below 1.
  void validate() const;
};

// Throws retarget::Error(mesh.source or `what` when it has none) when the mesh has more vertices
// or faces than `limits`, giving both counts and the option that raises the limit:
//   "head.obj: 1000000 vertices, more than the limit of 200000 (it keeps memory and time in
//    bounds); decimate the mesh, or raise the limit with --max-vertices 1000000"
void check_mesh_size(const Mesh& mesh, const MeshSizeLimits& limits, const std::string& what = "the mesh");

}  // namespace retarget
