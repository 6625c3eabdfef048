// Edge weights of the rest mesh shared by DR features and reconstruction, so that
// both sides of the round trip use one convention.
#pragma once

#include <Eigen/Core>
#include <string>

#include "geometry/mesh.h"
#include "geometry/mesh_topology.h"

namespace retarget {

enum class EdgeWeighting { cotangent, uniform };

// "cotangent" or "uniform"; throws retarget::Error naming `where` otherwise.
EdgeWeighting parse_edge_weighting(const std::string& text, const std::string& where);
const char* to_string(EdgeWeighting weighting);

// One weight per edge of `topology` (#E), computed on rest positions V (#V x 3).
// cotangent: w_ij = sum over the triangles at the edge of cot(angle opposite the edge),
// doubled on a boundary edge so boundary and interior weights have one scale; every
// cosine is clamped to [-0.99, 0.99] (thin and degenerate triangles give bounded, finite
// cotangents), negative sums are clamped to zero, and every weight is finally floored at
// 1e-4 x the mean weight so that no edge (and no vertex) drops out of the system.
// uniform: all ones.
Eigen::VectorXd edge_weights(const Positions& V, const EdgeTopology& topology, EdgeWeighting weighting);

}  // namespace retarget
