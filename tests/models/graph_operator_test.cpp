#include "models/graph_operator.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "core/error.h"
#include "tests/models/model_test_support.h"

namespace retarget {
namespace {

// Dense reference: L = I - D^-1/2 A D^-1/2 of the binary adjacency, lambda_max by eigvalsh.
torch::Tensor dense_reference(const torch::Tensor& edges, int64_t v) {
  torch::Tensor a = torch::zeros({v, v}, torch::kFloat64);
  for (int64_t k = 0; k < edges.size(0); ++k) {
    const int64_t i = edges[k][0].item<int64_t>(), j = edges[k][1].item<int64_t>();
    a[i][j] = 1.0;
    a[j][i] = 1.0;
  }
  const torch::Tensor d = a.sum(1).rsqrt();
  const torch::Tensor l = torch::eye(v, torch::kFloat64) - d.unsqueeze(1) * a * d.unsqueeze(0);
  const double lambda = torch::linalg::eigvalsh(l, "L").max().item<double>();
  return 2.0 * l / lambda - torch::eye(v, torch::kFloat64);
}

TEST_CASE("graph_operator of a 4-cycle is -A/2 (lambda_max = 2)", "[graph_operator]") {
  const torch::Tensor edges = torch::tensor({0, 1, 1, 2, 2, 3, 3, 0}, torch::kInt64).view({4, 2});
  const torch::Tensor op = graph_operator(edges, 4);
  CHECK(op.is_sparse());
  CHECK(op.is_coalesced());
  CHECK(op.scalar_type() == torch::kFloat32);
  CHECK(op.sizes() == torch::IntArrayRef({4, 4}));
  const torch::Tensor expected = torch::tensor({0.0, -0.5, 0.0, -0.5,  //
                                                -0.5, 0.0, -0.5, 0.0,  //
                                                0.0, -0.5, 0.0, -0.5,  //
                                                -0.5, 0.0, -0.5, 0.0})
                                     .view({4, 4});
  CHECK(torch::allclose(op.to_dense(), expected, 1e-5, 1e-5));
  // The bound lambda_max = 2 is exact here.
  GraphOperatorOptions bound;
  bound.bound_lambda_max = true;
  CHECK(torch::allclose(graph_operator(edges, 4, bound).to_dense(), expected, 1e-6, 1e-6));
}

TEST_CASE("graph_operator matches a dense computation on a triangulated grid", "[graph_operator]") {
  const torch::Tensor edges = test::grid_edges(3, 4);
  const torch::Tensor op = graph_operator(edges, 12);
  const torch::Tensor dense = op.to_dense().to(torch::kFloat64);
  CHECK(torch::allclose(dense, dense_reference(edges, 12), 1e-5, 1e-5));
  CHECK(torch::allclose(dense, dense.t()));
  const torch::Tensor eig = torch::linalg::eigvalsh(dense, "L");
  CHECK(eig.min().item<double>() >= -1.0 - 1e-5);
  CHECK(eig.max().item<double>() <= 1.0 + 1e-5);
  CHECK(eig.max().item<double>() == Approx(1.0).margin(1e-5));  // lambda_max maps to 1

  SECTION("repeated and reversed edges are the same edge (binary adjacency)") {
    const torch::Tensor doubled = torch::cat({edges, edges.flip({1}), edges});
    CHECK(torch::allclose(graph_operator(doubled, 12).to_dense(), op.to_dense()));
  }
}

TEST_CASE("graph_operator gives an isolated vertex the row of -I", "[graph_operator]") {
  // Path 0-1-2 plus isolated vertex 3.
  const torch::Tensor edges = torch::tensor({0, 1, 1, 2}, torch::kInt64).view({2, 2});
  const torch::Tensor dense = graph_operator(edges, 4).to_dense();
  CHECK(torch::allclose(dense[3], torch::tensor({0.0f, 0.0f, 0.0f, -1.0f})));
  CHECK(torch::allclose(dense.index({torch::indexing::Slice(0, 3), torch::indexing::Slice(0, 3)}).to(torch::kFloat64),
                        dense_reference(edges, 3), 1e-5, 1e-5));
  // No edges at all: L~ = -I.
  CHECK(torch::allclose(graph_operator(torch::zeros({0, 2}, torch::kInt64), 3).to_dense(), -torch::eye(3)));
}

TEST_CASE("graph_operator rejects bad input with a message", "[graph_operator]") {
  const torch::Tensor edges = torch::tensor({0, 1, 1, 4}, torch::kInt64).view({2, 2});
  CHECK_THROWS_AS(graph_operator(edges, 4), Error);
  CHECK_THROWS_WITH(graph_operator(edges, 4), "graph_operator: edge 1 (1, 4): vertex index 4 out of range [0, 4)");
  CHECK_THROWS_WITH(graph_operator(torch::tensor({0, -1}, torch::kInt64).view({1, 2}), 4),
                    "graph_operator: edge 0 (0, -1): vertex index -1 out of range [0, 4)");
  CHECK_THROWS_WITH(graph_operator(torch::tensor({0, 1, 2, 2}, torch::kInt64).view({2, 2}), 4),
                    "graph_operator: edge 1 (2, 2): self loop");
  CHECK_THROWS_WITH(graph_operator(torch::tensor({0, 1, 2}, torch::kInt64), 4),
                    Catch::StartsWith("graph_operator: expected edges as an int64 tensor [E, 2], got Long [3]"));
  CHECK_THROWS_WITH(graph_operator(torch::tensor({0.0f, 1.0f}).view({1, 2}), 4),
                    Catch::StartsWith("graph_operator: expected edges as an int64 tensor [E, 2], got Float"));
  CHECK_THROWS_WITH(graph_operator(edges, 0), "graph_operator: expected a positive vertex count, got 0");
  GraphOperatorOptions options;
  options.power_iterations = 0;
  CHECK_THROWS_WITH(graph_operator(edges, 5, options),
                    "graph_operator.power_iterations: expected a positive number, got 0");
}

}  // namespace
}  // namespace retarget
