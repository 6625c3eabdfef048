#include "geometry/mesh_topology.h"

#include <catch2/catch.hpp>

#include "geometry/cotangent_weights.h"
#include "test_support.h"

using namespace retarget;

TEST_CASE("edges of a closed sphere: Euler's formula, two opposite vertices each", "[mesh_topology]") {
  const Mesh sphere = test::uv_sphere(6, 8);
  const EdgeTopology topology = edge_topology(sphere.triangles);
  CHECK(sphere.vertex_count() - static_cast<int>(topology.edges.size()) + sphere.triangle_count() == 2);
  for (int e = 0; e < static_cast<int>(topology.edges.size()); ++e) {
    CHECK(topology.edges[e][0] < topology.edges[e][1]);
    CHECK(topology.opposite.size(e) == 2);
  }
  const CompressedRows neighbors = vertex_neighbors(topology, sphere.vertex_count());
  CHECK(neighbors.size(0) == 8);  // the pole sees the whole first ring
  const CompressedRows around = vertex_triangles(sphere.triangles, sphere.vertex_count());
  CHECK(around.size(0) == 8);
}

TEST_CASE("boundary edges have one opposite vertex; components are counted", "[mesh_topology]") {
  Mesh grid = test::quad_grid(2, 1, 2.0, 1.0, [](double, double) { return 0.0; });
  const EdgeTopology topology = edge_topology(grid.triangles);
  int boundary = 0;
  for (int e = 0; e < static_cast<int>(topology.edges.size()); ++e) boundary += topology.opposite.size(e) == 1;
  CHECK(boundary == 6);
  CHECK(connected_components(topology, grid.vertex_count()).count() == 1);
  // An extra isolated vertex is its own component.
  CHECK(connected_components(topology, grid.vertex_count() + 1).count() == 2);
}

TEST_CASE("cotangent weights: the right-isoceles known answer and clamping", "[cotangent_weights]") {
  // Two right triangles sharing the hypotenuse (0,3): opposite angles are 90 degrees -> cot 0.
  Mesh square = test::quad_grid(1, 1, 1.0, 1.0, [](double, double) { return 0.0; });
  const EdgeTopology topology = edge_topology(square.triangles);
  const Eigen::VectorXd w = edge_weights(square.vertices, topology, EdgeWeighting::cotangent);
  for (int e = 0; e < static_cast<int>(topology.edges.size()); ++e) {
    const auto [i, j] = topology.edges[e];
    if (i == 0 && j == 3) {
      CHECK(w[e] == Approx(1e-4 * 8.0 / 5.0));  // cot 90 = 0, floored at 1e-4 x the mean of the raw weights
    } else {
      CHECK(w[e] == Approx(2.0));  // boundary edge: 2 cot(45 degrees)
    }
  }
  CHECK(edge_weights(square.vertices, topology, EdgeWeighting::uniform) == Eigen::VectorXd::Ones(5));
  // A needle triangle: the clamped cosine bounds the cotangent.
  Positions needle(3, 3);
  needle << 0, 0, 0, 1, 0, 0, 0.5, 1e-9, 0;
  Triangles t(1, 3);
  t << 0, 1, 2;
  const Eigen::VectorXd wn = edge_weights(needle, edge_topology(t), EdgeWeighting::cotangent);
  CHECK(wn.allFinite());
  CHECK(wn.maxCoeff() <= 2 * 0.99 / std::sqrt(1 - 0.99 * 0.99) + 1e-9);
  CHECK_THROWS_WITH(parse_edge_weighting("cotan", "dr.weighting"),
                    Catch::Contains("dr.weighting") && Catch::Contains("\"cotan\""));
}
