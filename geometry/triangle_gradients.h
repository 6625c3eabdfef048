// Per-triangle deformation gradients in the construction of Sumner & Popovic 2004:
// a triangle (v1, v2, v3) gets a fourth vertex v4 = v1 + n / sqrt(|n|), n = (v2 - v1) x (v3 - v1),
// so that the frame [v2 - v1, v3 - v1, v4 - v1] is invertible and every column scales
// like an edge (a uniformly scaled triangle has a uniformly scaled frame).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "geometry/mesh.h"

namespace retarget {

// The 3x3 frame [b - a, c - a, n / sqrt(|n|)] (columns) of triangle (a, b, c), any units.
// A zero-area triangle gets a zero third column instead of NaNs.
Eigen::Matrix3d triangle_frame(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

// Rest-shape data of every triangle of a mesh, computed once.
struct TriangleFrames {
  // #T inverses of the rest frames; zero for invalid triangles.
  std::vector<Eigen::Matrix3d> inverse;
  // #T: 0 where the triangle is degenerate (area below 1e-10 x its longest edge squared,
  // or non-finite corners): its gradient is undefined and users give it zero weight.
  std::vector<char> valid;

  int size() const { return static_cast<int>(valid.size()); }
  int invalid_count() const;
};

// rest: #V x 3; triangles: #T x 3.
TriangleFrames triangle_frames(const Positions& rest, const Triangles& triangles);

// Deformation gradient of triangle t, frame(deformed) * frame(rest)^-1 (3x3, unitless): maps
// rest edges (and the scaled rest normal) to deformed ones. deformed: #V x 3 on the rest
// mesh's topology. The identity for an invalid triangle.
Eigen::Matrix3d deformation_gradient(const Positions& deformed, const Triangles& triangles,
                                     const TriangleFrames& frames, int t);

// The 3 x 4 operator G of one triangle: for one coordinate d, the row d of the deformation
// gradient equals G * (x1[d], x2[d], x3[d], x4[d])^T, where x1..x3 are the corners and x4
// the fourth vertex, all unknown. This is what makes the least-squares systems of
// deformation transfer decouple into one matrix with three right-hand sides.
// rest_inverse: the triangle's frame(rest)^-1.
Eigen::Matrix<double, 3, 4> gradient_operator(const Eigen::Matrix3d& rest_inverse);

}  // namespace retarget
