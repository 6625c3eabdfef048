#include "geometry/metrics.h"

#include <catch2/catch.hpp>

using namespace retarget;

TEST_CASE("vertex error: mean, max and the worst vertex", "[metrics]") {
  Positions a = Positions::Zero(4, 3), b = Positions::Zero(4, 3);
  b(1, 0) = 3;
  b(2, 1) = 4;
  const VertexError e = vertex_error(a, b, 10.0);
  CHECK(e.mean == Approx(17.5));
  CHECK(e.max == Approx(40));
  CHECK(e.worst_vertex == 2);
  CHECK_THROWS_WITH(vertex_error(a, Positions::Zero(3, 3)), Catch::Contains("4 and 3"));
}

TEST_CASE("the paper's unit: eye centres 10 cm apart, errors in mm", "[metrics]") {
  Positions face = Positions::Zero(6, 3);
  face.row(0) << -3, 0, 0;  // left eye landmarks around (-3, 0, 0)
  face.row(1) << -3, 1, 0;
  face.row(2) << -3, -1, 0;
  face.row(3) << 3, 0.5, 0;  // right eye around (3, 0, 0)
  face.row(4) << 3, -0.5, 0;
  const EyeLandmarks eyes{{0, 1, 2}, {3, 4}};
  // Eye centres 6 units apart -> 100 mm / 6 units.
  CHECK(millimetres_per_unit(face, eyes) == Approx(100.0 / 6.0));
  CHECK_THROWS_WITH(millimetres_per_unit(face, EyeLandmarks{{0, 9}, {3}}),
                    Catch::Contains("left eye landmarks[1]") && Catch::Contains("index 9"));
  CHECK_THROWS_WITH(millimetres_per_unit(face, EyeLandmarks{{}, {3}}), Catch::Contains("empty"));
  CHECK_THROWS_WITH(millimetres_per_unit(face, EyeLandmarks{{5}, {5}}), Catch::Contains("coincide"));
  CHECK(bounding_box_diagonal(face) == Approx(std::sqrt(36.0 + 4.0)));
}
