// Simple procedural meshes (grids, spheres, tubes) for demos, benchmarks and tests.
#pragma once

#include <functional>

#include "geometry/mesh.h"

namespace retarget {

// A (nx+1) x (ny+1) vertex grid of quads over [0, sx] x [0, sy] with z = height(x, y)
// (flat if height is empty). Faces are quads (fan-triangulated); the mesh has a boundary.
Mesh quad_grid(int nx, int ny, double sx, double sy, const std::function<double(double, double)>& height = {});

// A closed UV sphere of radius r: `rings` latitude bands, `segments` longitudes;
// triangles at the poles, quads elsewhere. 2 + (rings - 1) * segments vertices.
Mesh uv_sphere(int rings, int segments, double r = 1.0);

// An open tube along z (two boundary loops): radius r, length h, rings x segments quads.
Mesh tube(int rings, int segments, double r = 0.5, double h = 2.0);

}  // namespace retarget
