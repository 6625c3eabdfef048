#include "geometry/synthetic_deformations.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace retarget {

double smoothstep(double a, double b, double x) {
  const double t = std::clamp((x - a) / (b - a), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

Positions twist(const Positions& V, const Eigen::Vector3d& axis, const Eigen::Vector3d& centre, double degrees,
                double t0, double t1) {
  Positions out = V;
  for (int i = 0; i < V.rows(); ++i) {
    const Eigen::Vector3d p = V.row(i).transpose() - centre;
    const double angle = degrees * M_PI / 180 * smoothstep(t0, t1, p.dot(axis));
    out.row(i) = (Eigen::AngleAxisd(angle, axis) * p + centre).transpose();
  }
  return out;
}

Positions twist(const Positions& V, double degrees, double z0, double z1) {
  return twist(V, Eigen::Vector3d::UnitZ(), Eigen::Vector3d::Zero(), degrees, z0, z1);
}

Positions bend(const Positions& V, double degrees, double x0, double x1) {
  Positions out = V;
  const Eigen::Vector3d pivot(x0, 0, 0);
  for (int i = 0; i < V.rows(); ++i) {
    const double angle = degrees * M_PI / 180 * smoothstep(x0, x1, V(i, 0));
    out.row(i) =
        (Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()) * (V.row(i).transpose() - pivot) + pivot).transpose();
  }
  return out;
}

Positions bulge(const Positions& V, const Eigen::Vector3d& centre, double radius, const Eigen::Vector3d& direction,
                double amount) {
  Positions out = V;
  for (int i = 0; i < V.rows(); ++i) {
    const double r2 = (V.row(i).transpose() - centre).squaredNorm() / (radius * radius);
    out.row(i) += amount * std::exp(-r2) * direction.transpose();
  }
  return out;
}

Positions rigid_motion(const Positions& V, const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Positions out = (V * R.transpose()).rowwise() + t.transpose();
  return out;
}

}  // namespace retarget
