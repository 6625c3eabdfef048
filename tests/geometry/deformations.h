// Smooth test deformations shared by the DR-feature and reconstruction tests.
#pragma once

#include <Eigen/Geometry>
#include <cmath>

#include "geometry/mesh.h"

namespace retarget::test {

inline double smoothstep(double a, double b, double x) {
  const double t = std::clamp((x - a) / (b - a), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

// Twists the part of V above z = z0 about the z axis, ramping smoothly up to `degrees`
// at z = z1 (the part below z0 stays put).
inline Positions twist(const Positions& V, double degrees, double z0, double z1) {
  Positions out = V;
  for (int i = 0; i < V.rows(); ++i) {
    const double angle = degrees * M_PI / 180 * smoothstep(z0, z1, V(i, 2));
    const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    out.row(i) = (R * V.row(i).transpose()).transpose();
  }
  return out;
}

// Bends a patch in the x-z plane: x beyond x0 curls around the y axis by up to `degrees`.
inline Positions bend(const Positions& V, double degrees, double x0, double x1) {
  Positions out = V;
  for (int i = 0; i < V.rows(); ++i) {
    const double angle = degrees * M_PI / 180 * smoothstep(x0, x1, V(i, 0));
    const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()).toRotationMatrix();
    const Eigen::Vector3d pivot(x0, 0, 0);
    out.row(i) = (R * (V.row(i).transpose() - pivot) + pivot).transpose();
  }
  return out;
}

// A smooth bulge: points near `centre` move along `direction` by up to `amount`.
inline Positions bulge(const Positions& V, const Eigen::Vector3d& centre, double radius, const Eigen::Vector3d& direction,
                       double amount) {
  Positions out = V;
  for (int i = 0; i < V.rows(); ++i) {
    const double r2 = (V.row(i).transpose() - centre).squaredNorm() / (radius * radius);
    out.row(i) += amount * std::exp(-r2) * direction.transpose();
  }
  return out;
}

inline Positions rigid_motion(const Positions& V, const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Positions out = (V * R.transpose()).rowwise() + t.transpose();
  return out;
}

}  // namespace retarget::test
