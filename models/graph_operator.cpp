#include "models/graph_operator.h"

#include <algorithm>
#include <cmath>

#include "core/config.h"
#include "core/error.h"
#include "geometry/mesh_topology.h"

namespace retarget {

void GraphOperatorOptions::validate(const std::string& key_path) const {
  require_positive(static_cast<double>(power_iterations), key_path + ".power_iterations");
  require_positive(tolerance, key_path + ".tolerance");
}

double largest_eigenvalue(const torch::Tensor& matrix, int64_t iterations, double tolerance) {
  TORCH_CHECK(matrix.is_sparse() && matrix.dim() == 2 && matrix.size(0) == matrix.size(1),
              "largest_eigenvalue: expected a square sparse matrix, got ", matrix.sizes());
  const torch::Tensor m = matrix.to(torch::kFloat64);
  const int64_t n = m.size(0);
  // A fixed, non-symmetric start vector: deterministic and (generically) not orthogonal to the
  // top eigenvector, unlike a constant vector, which is the null vector of L on connected graphs.
  torch::Tensor v = torch::sin(torch::arange(n, torch::kFloat64) * 1.2345 + 0.5) + 1.5;
  v = v / v.norm();
  double lambda = 0.0;
  for (int64_t it = 0; it < iterations; ++it) {
    const torch::Tensor w = torch::mm(m, v.unsqueeze(1)).squeeze(1);
    const double next = torch::dot(v, w).item<double>();  // Rayleigh quotient, |v| = 1
    const double norm = w.norm().item<double>();
    if (norm == 0.0) return 0.0;  // v in the null space: every eigenvalue seen is 0
    v = w / norm;
    const bool converged = it > 0 && std::abs(next - lambda) <= tolerance * std::max(1.0, std::abs(next));
    lambda = next;
    if (converged) break;
  }
  return lambda;
}

torch::Tensor graph_operator(const torch::Tensor& edges, int64_t vertex_count, const GraphOperatorOptions& options) {
  options.validate();
  const std::string where = "graph_operator";
  if (vertex_count <= 0) throw Error(where, "expected a positive vertex count, got " + std::to_string(vertex_count));
  if (edges.scalar_type() != torch::kInt64 || edges.dim() != 2 || edges.size(1) != 2) {
    throw Error(where, "expected edges as an int64 tensor [E, 2], got " + std::string(toString(edges.scalar_type())) +
                           " " + c10::str(edges.sizes()));
  }
  const torch::Tensor e = edges.to(torch::kCPU).contiguous();
  const auto acc = e.accessor<int64_t, 2>();
  for (int64_t k = 0; k < e.size(0); ++k) {
    for (int c = 0; c < 2; ++c) {
      if (acc[k][c] < 0 || acc[k][c] >= vertex_count) {
        throw Error(where, "edge " + std::to_string(k) + " (" + std::to_string(acc[k][0]) + ", " +
                               std::to_string(acc[k][1]) + "): vertex index " + std::to_string(acc[k][c]) +
                               " out of range [0, " + std::to_string(vertex_count) + ")");
      }
    }
    if (acc[k][0] == acc[k][1]) {
      throw Error(where, "edge " + std::to_string(k) + " (" + std::to_string(acc[k][0]) + ", " +
                             std::to_string(acc[k][1]) + "): self loop");
    }
  }

  const auto f64 = torch::TensorOptions().dtype(torch::kFloat64);
  // Binary adjacency: both directions, duplicates merged by coalesce and reset to 1.
  const torch::Tensor rows = torch::cat({e.select(1, 0), e.select(1, 1)});
  const torch::Tensor cols = torch::cat({e.select(1, 1), e.select(1, 0)});
  torch::Tensor adjacency = torch::sparse_coo_tensor(torch::stack({rows, cols}), torch::ones({rows.size(0)}, f64),
                                                     {vertex_count, vertex_count})
                                .coalesce();
  const torch::Tensor adj_index = adjacency.indices();
  const torch::Tensor degree =
      torch::zeros({vertex_count}, f64).index_add_(0, adj_index[0], torch::ones({adj_index.size(1)}, f64));
  const torch::Tensor inv_sqrt = torch::where(degree > 0, degree.clamp_min(1.0).rsqrt(), torch::zeros_like(degree));

  // L: off-diagonal -d_i^-1/2 d_j^-1/2, diagonal 1 (0 for isolated vertices).
  const torch::Tensor diag = torch::arange(vertex_count, torch::kInt64);
  const torch::Tensor index = torch::cat({adj_index, torch::stack({diag, diag})}, 1);
  const torch::Tensor values =
      torch::cat({-inv_sqrt.index_select(0, adj_index[0]) * inv_sqrt.index_select(0, adj_index[1]),
                  (degree > 0).to(torch::kFloat64)});
  const torch::Tensor laplacian = torch::sparse_coo_tensor(index, values, {vertex_count, vertex_count}).coalesce();

  double lambda_max = 2.0;
  if (!options.bound_lambda_max) {
    lambda_max = largest_eigenvalue(laplacian, options.power_iterations, options.tolerance);
    // All-isolated graphs have L = 0; any positive scale gives L~ = -I.
    if (!(lambda_max > 1e-12)) lambda_max = 2.0;
  }
  const torch::Tensor l_index = laplacian.indices();
  const torch::Tensor on_diagonal = (l_index[0] == l_index[1]).to(torch::kFloat64);
  const torch::Tensor scaled = laplacian.values() * (2.0 / lambda_max) - on_diagonal;
  return torch::sparse_coo_tensor(l_index, scaled.to(torch::kFloat32), {vertex_count, vertex_count}).coalesce();
}

torch::Tensor mesh_graph_operator(const Mesh& mesh) {
  const EdgeTopology topology = edge_topology(mesh.triangles);
  torch::Tensor edges = torch::empty({static_cast<int64_t>(topology.edges.size()), 2}, torch::kInt64);
  auto e = edges.accessor<int64_t, 2>();
  for (size_t i = 0; i < topology.edges.size(); ++i) {
    e[static_cast<int64_t>(i)][0] = topology.edges[i][0];
    e[static_cast<int64_t>(i)][1] = topology.edges[i][1];
  }
  return graph_operator(edges, mesh.vertex_count());
}

}  // namespace retarget
