// The graph operator of the Chebyshev graph convolutions: the rescaled normalised Laplacian of a
// mesh's binary adjacency (Defferrard et al. 2016; method notes, "Networks").
//
//   L  = I - D^-1/2 A D^-1/2          A: binary adjacency (an edge given twice counts once)
//   L~ = 2 L / lambda_max - I         eigenvalues of L~ in [-1, 1]
//
// Isolated vertices (degree 0): L is formed as D^-1/2 (D - A) D^-1/2 with D^-1/2 = 0 there, so
// an isolated vertex has a zero row in L and the row of -I in L~ (its Chebyshev terms are then
// x, -x, x, ...; it only sees itself). For every other vertex this equals I - D^-1/2 A D^-1/2.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <string>

#include "geometry/mesh.h"

namespace retarget {

struct GraphOperatorOptions {
  // Use the bound lambda_max = 2 (exact for bipartite graphs) instead of power iteration.
  bool bound_lambda_max = false;
  // Power iteration on L (float64): at most this many steps ...
  int64_t power_iterations = 500;
  // ... stopping when the Rayleigh quotient changes by less than this (relative).
  double tolerance = 1e-10;

  void validate(const std::string& key_path = "graph_operator") const;  // throws retarget::Error
};

// Largest eigenvalue of a symmetric positive semi-definite sparse matrix (here L), by power
// iteration with the Rayleigh quotient, in float64. The estimate approaches lambda_max from
// below, so it is at most lambda_max (plus rounding). Deterministic (fixed start vector).
//   matrix: [V, V] sparse COO, any floating dtype.  Returns lambda_max (>= 0).
double largest_eigenvalue(const torch::Tensor& matrix, int64_t iterations, double tolerance);

// Builds L~ from an undirected edge list.
//   edges:        [E, 2] int64, vertex indices in [0, vertex_count); (i, j) and (j, i) and
//                 repeated edges are the same edge. E may be 0.
//   vertex_count: V > 0.
//   returns:      [V, V] sparse COO float32, coalesced, symmetric, with all V diagonal entries
//                 stored.
// Throws retarget::Error for a bad edge tensor, an out-of-range index or a self loop (naming the
// edge row), and for V <= 0.
torch::Tensor graph_operator(const torch::Tensor& edges, int64_t vertex_count,
                             const GraphOperatorOptions& options = {});

// The operator of a mesh: graph_operator() of the edges of its triangulation (polygons are
// fan-triangulated, so a quad adds its diagonal). [V, V] sparse COO float32.
torch::Tensor mesh_graph_operator(const Mesh& mesh);

}  // namespace retarget
