#include "synthetic/geometry_demo.h"

#include <catch2/catch.hpp>
#include <filesystem>

#include "core/error.h"
#include "geometry/mesh_io.h"
#include "test_support.h"

using namespace retarget;

TEST_CASE("the geometry demo runs end to end and writes readable meshes", "[geometry_demo]") {
  GeometryDemoOptions options;
  options.out = test::scratch_dir("geometry_demo").string();
  options.source_resolution = 40;
  options.target_columns = 27;
  options.target_rows = 33;
  const std::vector<GeometryDemoRow> rows = run_geometry_demo(options);
  REQUIRE(rows.size() == 4);
  for (const GeometryDemoRow& row : rows) {
    INFO(row.expression);
    CHECK(row.roundtrip_mean_mm < 0.1);
    // The analytic expressions move the face by several mm; the transfer must follow them.
    CHECK(row.transfer_mean_mm < 3.0);
    const Mesh truth = read_mesh(options.out + "/target_truth/" + row.expression + ".obj");
    const Mesh moved = read_mesh(options.out + "/target/" + row.expression + ".obj");
    CHECK(moved.vertex_count() == truth.vertex_count());
    CHECK(moved.faces.indices == truth.faces.indices);
  }
}

TEST_CASE("the demo refuses options that cannot work", "[geometry_demo]") {
  GeometryDemoOptions options;
  options.source_resolution = 3;
  CHECK_THROWS_WITH(run_geometry_demo(options), Catch::Contains("demo.source_resolution"));
}
