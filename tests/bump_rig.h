// A rig controller for the tests' ball rigs: a smooth bump along the normal around one spot of a
// ball of radius `radius` centred at the origin, amplitude * exp(-d^2 / width) with d the distance
// from the vertex's direction to the spot's (units of the ball's radius).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <string>
#include <utility>

#include "geometry/rig.h"

namespace retarget::test {

inline Controller bump_controller(const std::string& name, const Positions& ball, double radius,
                                  const Eigen::RowVector3d& spot, double amplitude, double width,
                                  std::pair<double, double> range) {
  Controller c;
  c.name = name;
  c.offset = Positions::Zero(ball.rows(), 3);
  for (Eigen::Index i = 0; i < ball.rows(); ++i) {
    const double d2 = (ball.row(i) / radius - spot.normalized()).squaredNorm();
    c.offset.row(i) = amplitude * std::exp(-d2 / width) * ball.row(i).normalized();
  }
  c.min = range.first;
  c.max = range.second;
  return c;
}

}  // namespace retarget::test
