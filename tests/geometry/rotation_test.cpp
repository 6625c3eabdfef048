#include "geometry/rotation.h"

#include <Eigen/Geometry>
#include <catch2/catch.hpp>

using namespace retarget;

TEST_CASE("rotation log and exp are inverse near 0, in between and near pi", "[rotation]") {
  const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  for (double angle : {0.0, 1e-12, 1e-7, 1e-3, 0.5, 2.0, M_PI - 1e-3, M_PI - 1e-7, M_PI - 1e-10}) {
    INFO("angle " << angle);
    const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    const Eigen::Vector3d r = rotation_log(R);
    CHECK(std::abs(r.norm() - angle) < 1e-9);
    if (angle > 1e-6) CHECK((r.normalized() - axis).norm() < 1e-7);
    CHECK((rotation_exp(r) - R).norm() < 1e-12);
    CHECK((rotation_exp(angle * axis) - R).norm() < 1e-12);
  }
}

TEST_CASE("exactly pi gives a rotation vector of length pi on the axis", "[rotation]") {
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, 2) / 3.0;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(M_PI, axis).toRotationMatrix();
  const Eigen::Vector3d r = rotation_log(R);
  CHECK(std::abs(r.norm() - M_PI) < 1e-9);
  CHECK(std::abs(std::abs(r.normalized().dot(axis)) - 1) < 1e-9);  // either sign is the same rotation
  CHECK((rotation_exp(r) - R).norm() < 1e-9);
}

TEST_CASE("polar decomposition: T = R S with R a rotation and S symmetric", "[rotation]") {
  const Eigen::Matrix3d R0 = Eigen::AngleAxisd(1.2, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
  Eigen::Matrix3d S0;
  S0 << 1.5, 0.2, 0.1, 0.2, 0.8, -0.3, 0.1, -0.3, 1.1;
  struct Case {
    const char* name;
    Eigen::Matrix3d T;
  };
  Eigen::Matrix3d reflection = Eigen::Matrix3d::Identity();
  reflection(2, 2) = -1;
  Eigen::Matrix3d singular = R0;
  singular.col(2).setZero();
  const std::vector<Case> cases = {
      {"identity", Eigen::Matrix3d::Identity()}, {"rotation", R0},
      {"rotation times stretch", R0 * S0},       {"strong stretch", R0 * Eigen::Vector3d(50, 1, 0.02).asDiagonal()},
      {"reflection", R0 * reflection * S0},      {"rank two", singular},
      {"zero", Eigen::Matrix3d::Zero()},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    const PolarDecomposition p = polar_decomposition(c.T);
    CHECK(p.rotation.allFinite());
    CHECK(p.stretch.allFinite());
    CHECK((p.rotation * p.rotation.transpose() - Eigen::Matrix3d::Identity()).norm() < 1e-8);
    CHECK(std::abs(p.rotation.determinant() - 1) < 1e-8);
    CHECK((p.stretch - p.stretch.transpose()).norm() < 1e-12);
    CHECK((p.rotation * p.stretch - c.T).norm() < 1e-9 * std::max(1.0, c.T.norm()));
  }
  const PolarDecomposition p = polar_decomposition(R0 * S0);
  CHECK((p.rotation - R0).norm() < 1e-8);
  CHECK((p.stretch - S0).norm() < 1e-8);
}
