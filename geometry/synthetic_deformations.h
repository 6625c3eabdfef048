// Smooth analytic deformations of a mesh (twists, bends, bulges, rigid motions), for
// checking DR features and reconstruction on any mesh, including real ones.
#pragma once

#include <Eigen/Core>

#include "geometry/mesh.h"

namespace retarget {

// 0 below a, 1 above b, a smooth cubic ramp in between.
double smoothstep(double a, double b, double x);

// Twists V (#V x 3) about the line through `centre` along `axis` (unit): a vertex whose
// coordinate along the axis is t turns by degrees * smoothstep(t0, t1, t).
Positions twist(const Positions& V, const Eigen::Vector3d& axis, const Eigen::Vector3d& centre, double degrees,
                double t0, double t1);
// The same about the z axis through the origin (z between z0 and z1 ramps up).
Positions twist(const Positions& V, double degrees, double z0, double z1);

// Bends a patch: points beyond x = x0 turn about the y axis through (x0, 0, 0), ramping to
// `degrees` at x1.
Positions bend(const Positions& V, double degrees, double x0, double x1);

// Points near `centre` (Gaussian of `radius`) move along `direction` by up to `amount`.
Positions bulge(const Positions& V, const Eigen::Vector3d& centre, double radius, const Eigen::Vector3d& direction,
                double amount);

// x -> R x + t for every row.
Positions rigid_motion(const Positions& V, const Eigen::Matrix3d& R, const Eigen::Vector3d& t);

}  // namespace retarget
