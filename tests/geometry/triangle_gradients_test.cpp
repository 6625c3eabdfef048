#include "geometry/triangle_gradients.h"

#include <Eigen/Geometry>
#include <catch2/catch.hpp>

#include "test_support.h"

using namespace retarget;

TEST_CASE("a triangle's frame scales like its edges", "[triangle_gradients]") {
  const Eigen::Vector3d a(0.1, 0.2, 0.3), b(1.4, 0.1, 0.2), c(0.5, 1.1, -0.4);
  const Eigen::Matrix3d frame = triangle_frame(a, b, c);
  CHECK((frame.col(2).squaredNorm() - (b - a).cross(c - a).norm()) < 1e-14);
  CHECK(std::abs(frame.col(2).dot(b - a)) < 1e-14);
  const Eigen::Matrix3d scaled = triangle_frame(3 * a, 3 * b, 3 * c);
  CHECK((scaled - 3 * frame).norm() < 1e-13);
}

TEST_CASE("gradients of similarity and affine maps", "[triangle_gradients]") {
  const Mesh patch = test::bumpy_patch(6);
  const TriangleFrames frames = triangle_frames(patch.vertices, patch.triangles);
  REQUIRE(frames.invalid_count() == 0);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  const Eigen::Vector3d shift(3, -1, 2);
  const Positions moved = ((1.7 * patch.vertices * R.transpose()).rowwise() + shift.transpose());
  Eigen::Matrix3d A;
  A << 1.2, 0.3, -0.1, 0.0, 0.8, 0.2, 0.1, -0.2, 1.1;
  const Positions sheared = patch.vertices * A.transpose();
  for (int t = 0; t < patch.triangle_count(); ++t) {
    // A similarity maps the scaled normal to the scaled normal: the gradient is the map.
    CHECK((deformation_gradient(moved, patch.triangles, frames, t) - 1.7 * R).norm() < 1e-12);
    // A general linear map is reproduced on the triangle's plane.
    const Eigen::Matrix3d Q = deformation_gradient(sheared, patch.triangles, frames, t);
    const Eigen::Vector3d e1 = patch.vertices.row(patch.triangles(t, 1)) - patch.vertices.row(patch.triangles(t, 0));
    const Eigen::Vector3d e2 = patch.vertices.row(patch.triangles(t, 2)) - patch.vertices.row(patch.triangles(t, 0));
    CHECK((Q * e1 - A * e1).norm() < 1e-12);
    CHECK((Q * e2 - A * e2).norm() < 1e-12);
  }
}

TEST_CASE("the gradient operator is the gradient, one coordinate at a time", "[triangle_gradients]") {
  const Mesh patch = test::bumpy_patch(4);
  const TriangleFrames frames = triangle_frames(patch.vertices, patch.triangles);
  Positions deformed = patch.vertices;
  for (int i = 0; i < deformed.rows(); ++i)
    deformed.row(i) += Eigen::RowVector3d(0.1 * std::sin(i), 0.05 * (i % 3), 0.02 * i);
  for (int t = 0; t < patch.triangle_count(); ++t) {
    const auto tri = patch.triangles.row(t);
    const Eigen::Matrix3d frame = triangle_frame(deformed.row(tri[0]), deformed.row(tri[1]), deformed.row(tri[2]));
    Eigen::Matrix<double, 3, 4> X;  // corners and the fourth vertex, as columns
    X << deformed.row(tri[0]).transpose(), deformed.row(tri[1]).transpose(), deformed.row(tri[2]).transpose(),
        deformed.row(tri[0]).transpose() + frame.col(2);
    const Eigen::Matrix<double, 3, 4> G = gradient_operator(frames.inverse[t]);
    const Eigen::Matrix3d Q = deformation_gradient(deformed, patch.triangles, frames, t);
    for (int d = 0; d < 3; ++d) CHECK((G * X.row(d).transpose() - Q.row(d).transpose()).norm() < 1e-12);
  }
}

TEST_CASE("degenerate triangles are flagged and give no NaNs", "[triangle_gradients]") {
  Positions V(4, 3);
  V << 0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0;
  Triangles F(3, 3);
  F << 0, 1, 2,  // collinear
      0, 0, 3,   // repeated corner
      0, 1, 3;   // fine
  const TriangleFrames frames = triangle_frames(V, F);
  CHECK(frames.invalid_count() == 2);
  CHECK(frames.valid == std::vector<char>{0, 0, 1});
  CHECK(triangle_frame(V.row(0), V.row(1), V.row(2)).allFinite());
  for (int t = 0; t < 3; ++t) {
    CHECK(frames.inverse[t].allFinite());
    CHECK(deformation_gradient(2 * V, F, frames, t).allFinite());
  }
  CHECK(deformation_gradient(2 * V, F, frames, 0) == Eigen::Matrix3d::Identity());
}
