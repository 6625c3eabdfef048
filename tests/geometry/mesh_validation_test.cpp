#include "geometry/mesh_validation.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include "core/error.h"
#include "test_support.h"

using Catch::Contains;
using retarget::Error;
using retarget::Mesh;
using retarget::test::error_of;

namespace {

Mesh grid(int nx, int ny) {
  return retarget::test::quad_grid(nx, ny, 1.0, 1.0, [](double x, double y) { return 0.1 * x * y; });
}

Mesh with_faces(Mesh mesh, const std::vector<std::vector<int>>& faces) {
  mesh.faces = retarget::Polygons{};
  for (const auto& face : faces) mesh.faces.add(face.data(), static_cast<int>(face.size()));
  retarget::triangulate(mesh);
  return mesh;
}

}  // namespace

TEST_CASE("report counts for clean meshes", "[mesh_validation]") {
  SECTION("an open quad grid") {
    const Mesh mesh = grid(3, 2);
    const retarget::MeshReport report = retarget::validate_mesh(mesh);
    CHECK(report.vertex_count == 12);
    CHECK(report.face_count == 6);
    CHECK(report.triangle_count == 12);
    CHECK(report.edge_count == 3 * 3 + 4 * 2);
    CHECK(report.boundary_edges == 2 * (3 + 2));
    CHECK(report.nonmanifold_edges == 0);
    CHECK(report.inconsistent_edges == 0);
    CHECK(report.degenerate_triangles == 0);
    CHECK(report.degenerate_faces == 0);
    CHECK(report.first_degenerate_face == -1);
    CHECK(report.unreferenced_vertices == 0);
    CHECK(report.bounding_box_diagonal == Approx(std::sqrt(2.0 + 0.01)));
  }
  SECTION("a closed sphere with triangles and quads") {
    const retarget::MeshReport report = retarget::validate_mesh(retarget::test::uv_sphere(6, 8));
    CHECK(report.boundary_edges == 0);
    CHECK(report.nonmanifold_edges == 0);
    CHECK(report.inconsistent_edges == 0);
    CHECK(report.edge_count == 8 * 6 + 8 * 5);  // meridians + parallels
  }
  SECTION("a tube has two boundary loops") {
    CHECK(retarget::validate_mesh(retarget::test::tube(3, 10)).boundary_edges == 20);
  }
}

TEST_CASE("degenerate triangles are counted, not thrown", "[mesh_validation]") {
  Mesh mesh = grid(2, 1);  // vertices 0 1 2 along y = 0, 3 4 5 along y = 1
  mesh = with_faces(mesh, {{0, 1, 4, 3}, {1, 2, 5, 4}, {0, 1, 1}});
  mesh.vertices.row(5) = mesh.vertices.row(2);  // face 1's fan triangle (1, 2, 5) has zero area
  // face 2 repeats vertex 1
  const retarget::MeshReport report = retarget::validate_mesh(mesh);
  CHECK(report.degenerate_triangles == 2);
  CHECK(report.degenerate_faces == 2);
  CHECK(report.first_degenerate_face == 1);
}

TEST_CASE("degenerate area is relative to the mesh size", "[mesh_validation]") {
  for (double scale : {1e-4, 1.0, 1e4}) {
    INFO(scale);
    Mesh mesh = grid(4, 4);
    mesh.vertices *= scale;
    CHECK(retarget::validate_mesh(mesh).degenerate_triangles == 0);
    // Vertex 6 a hair (1e-9 of the size) from vertex 1: a sliver of area ~1e-10 diag^2, kept.
    mesh.vertices.row(6) = mesh.vertices.row(1) + Eigen::RowVector3d(0, 1e-9 * scale, 0);
    CHECK(retarget::validate_mesh(mesh).degenerate_triangles == 0);
    mesh.vertices.row(6) = mesh.vertices.row(1);
    CHECK(retarget::validate_mesh(mesh).degenerate_triangles == 2);
  }
}

TEST_CASE("unreferenced vertices, non-manifold and flipped faces are counted", "[mesh_validation]") {
  SECTION("unreferenced") {
    Mesh mesh = grid(2, 2);
    mesh = with_faces(mesh, {{0, 1, 4, 3}});
    CHECK(retarget::validate_mesh(mesh).unreferenced_vertices == 5);
  }
  SECTION("three faces on one edge") {
    Mesh mesh;
    mesh.vertices.resize(5, 3);
    mesh.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1;
    mesh = with_faces(mesh, {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
    const retarget::MeshReport report = retarget::validate_mesh(mesh);
    CHECK(report.nonmanifold_edges == 1);
    CHECK(report.boundary_edges == 6);
  }
  SECTION("a flipped face") {
    Mesh mesh = grid(3, 3);
    std::reverse(mesh.faces.indices.begin() + mesh.faces.offsets[4],
                 mesh.faces.indices.begin() + mesh.faces.offsets[5]);
    retarget::triangulate(mesh);
    CHECK(retarget::validate_mesh(mesh).inconsistent_edges == 4);  // the centre quad's four edges
  }
}

TEST_CASE("invalid meshes throw with the file, the element and the value", "[mesh_validation]") {
  Mesh mesh = grid(4, 4);
  mesh.source = "face.obj";

  SECTION("no vertices") {
    Mesh empty;
    empty.source = "empty.obj";
    CHECK_THAT(error_of([&] { retarget::validate_mesh(empty); }), Contains("empty.obj: ") && Contains("no vertices"));
  }
  SECTION("no faces") {
    mesh.faces = retarget::Polygons{};
    retarget::triangulate(mesh);
    CHECK_THAT(error_of([&] { retarget::validate_mesh(mesh); }), Contains("face.obj: ") && Contains("no faces"));
  }
  SECTION("a name for meshes built in code") {
    Mesh empty;
    CHECK_THAT(error_of([&] { retarget::validate_mesh(empty); }), Contains("mesh: ") && Contains("no vertices"));
  }
  SECTION("NaN") {
    mesh.vertices(17, 1) = std::numeric_limits<double>::quiet_NaN();
    CHECK_THAT(error_of([&] { retarget::validate_mesh(mesh); }),
               Contains("face.obj: vertex 17 has a non-finite coordinate (y = nan)"));
  }
  SECTION("Inf") {
    mesh.vertices(3, 2) = -std::numeric_limits<double>::infinity();
    CHECK_THAT(error_of([&] { retarget::validate_mesh(mesh); }),
               Contains("face.obj: vertex 3 has a non-finite coordinate (z = -inf)"));
  }
  SECTION("face index out of range") {
    mesh.faces.indices[mesh.faces.offsets[2] + 1] = 25;
    CHECK_THAT(error_of([&] { retarget::validate_mesh(mesh); }),
               Contains("face.obj: face 2 refers to vertex 25, but the mesh has 25 vertices"));
    mesh.faces.indices[mesh.faces.offsets[2] + 1] = -1;
    CHECK_THAT(error_of([&] { retarget::validate_mesh(mesh); }), Contains("face 2 refers to vertex -1"));
  }
  SECTION("face with two vertices") {
    mesh = with_faces(mesh, {{0, 1, 6, 5}, {1, 2}});
    CHECK_THAT(error_of([&] { retarget::validate_mesh(mesh); }),
               Contains("face.obj: face 1 has 2 vertices; a face needs at least 3"));
  }
}

TEST_CASE("require_same_topology names both counts and both files", "[mesh_validation]") {
  Mesh rest;
  rest.vertices = retarget::Positions::Zero(11248, 3);
  rest.source = "neutral.obj";
  Mesh frame;
  frame.vertices = retarget::Positions::Zero(11000, 3);
  frame.source = "frame_0003.obj";
  CHECK_THAT(error_of([&] { retarget::require_same_topology(rest, frame); }),
             Contains("frame_0003.obj has 11,000 vertices but the rest mesh neutral.obj has 11,248"));

  SECTION("faces") {
    Mesh a = grid(3, 3), b = grid(3, 3);
    a.source = "neutral.obj";
    b.source = "smile.obj";
    CHECK_NOTHROW(retarget::require_same_topology(a, b));
    b.vertices *= 2;  // positions may differ
    CHECK_NOTHROW(retarget::require_same_topology(a, b));

    std::swap(b.faces.indices[b.faces.offsets[5]], b.faces.indices[b.faces.offsets[5] + 1]);
    CHECK_THAT(error_of([&] { retarget::require_same_topology(a, b); }),
               Contains("smile.obj: face 5 is (7 6 11 10) but in the rest mesh neutral.obj it is (6 7 11 10)"));

    Mesh c = with_faces(grid(3, 3), {{0, 1, 5, 4}});
    c.source = "one_face.obj";
    CHECK_THAT(error_of([&] { retarget::require_same_topology(a, c); }),
               Contains("one_face.obj has 1 faces but the rest mesh neutral.obj has 9"));
  }
  SECTION("unnamed meshes") {
    rest.source.clear();
    frame.source.clear();
    CHECK_THAT(error_of([&] { retarget::require_same_topology(rest, frame); }),
               Contains("the mesh has 11,000 vertices but the rest mesh has 11,248"));
  }
}
