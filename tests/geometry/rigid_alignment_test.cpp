#include "geometry/rigid_alignment.h"

#include <Eigen/Geometry>
#include <catch2/catch.hpp>

#include "geometry/metrics.h"
#include "test_support.h"

using namespace retarget;

TEST_CASE("Kabsch recovers a rotation and translation; Umeyama also the scale", "[rigid_alignment]") {
  const Positions P = test::bumpy_patch(8).vertices;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(2.9, Eigen::Vector3d(0.2, 1, -0.4).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(1, -2, 0.5);
  const Positions Q = ((P * R.transpose()).rowwise() + t.transpose());
  const RigidTransform rigid = rigid_alignment(P, Q);
  CHECK((rigid.rotation - R).norm() < 1e-10);
  CHECK((rigid.translation - t).norm() < 1e-10);
  CHECK(vertex_error(rigid.apply(P), Q).max < 1e-10);

  const Positions scaled = ((2.5 * P * R.transpose()).rowwise() + t.transpose());
  RigidAlignmentOptions options;
  options.with_scale = true;
  const RigidTransform similarity = rigid_alignment(P, scaled, options);
  CHECK(similarity.scale == Approx(2.5).epsilon(1e-10));
  CHECK(vertex_error(similarity.apply(P), scaled).max < 1e-9);
}

TEST_CASE("a mirrored target never yields a reflection", "[rigid_alignment]") {
  const Positions sphere = test::uv_sphere(5, 6).vertices;
  const Positions P = (sphere.rowwise() + Eigen::RowVector3d(0.1, 0.2, 0.3)).eval();
  Positions mirrored = P;
  mirrored.col(0) *= -1;
  CHECK(rigid_alignment(P, mirrored).rotation.determinant() == Approx(1.0));
}

TEST_CASE("weights select the points that matter", "[rigid_alignment]") {
  Positions P(4, 3), Q(4, 3);
  P << 0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5;
  Q = P;
  Q.row(3) << 50, -3, 8;  // an outlier with zero weight
  RigidAlignmentOptions options;
  options.weights = Eigen::Vector4d(1, 1, 1, 0);
  CHECK(vertex_error(rigid_alignment(P, Q, options).apply(P).topRows(3), P.topRows(3)).max < 1e-12);
}

TEST_CASE("bad alignment input says what is wrong", "[rigid_alignment]") {
  const Positions P = Positions::Random(5, 3);
  CHECK_THROWS_WITH(rigid_alignment(P, Positions::Random(4, 3)), Catch::Contains("5 and 4"));
  RigidAlignmentOptions options;
  options.weights = Eigen::VectorXd::Zero(5);
  CHECK_THROWS_WITH(rigid_alignment(P, P, options), Catch::Contains("all weights are zero"));
  options.weights = Eigen::VectorXd::Ones(3);
  CHECK_THROWS_WITH(rigid_alignment(P, P, options), Catch::Contains("3 weights for 5 points"));
}
