// Boundary loops of a triangle surface: the rims of its holes (an eye socket, a mouth cut open,
// the neck), each as an ordered cycle of vertices.
#pragma once

#include <vector>

#include "geometry/mesh.h"

namespace retarget {

// Each loop lists its vertices in order along the rim (the direction of the boundary edges in
// their triangles), first vertex not repeated at the end. A boundary edge is an edge of exactly
// one triangle. Where the boundary touches itself (a vertex with more than two boundary edges)
// the walk takes the edges in order of appearance, so every boundary edge is in exactly one
// loop. Loops are sorted by length, longest first (ties: lowest first vertex).
std::vector<std::vector<int>> boundary_loops(const Triangles& triangles);

}  // namespace retarget
