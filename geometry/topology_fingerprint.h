// A short name for a mesh topology, so that files made for one topology (datasets, models,
// bundles) can refuse a mesh of another without storing its triangles.
#pragma once

#include <string>

#include "geometry/mesh.h"

namespace retarget {

// 64-bit FNV-1a over the vertex count and the triangle list (mesh.triangles, #T x 3, row by
// row, each index as 4 little-endian bytes), as 16 lowercase hex digits. Positions do not
// enter: every mesh of one topology, in any pose or unit, has the same fingerprint.
std::string topology_fingerprint(const Mesh& mesh);

}  // namespace retarget
