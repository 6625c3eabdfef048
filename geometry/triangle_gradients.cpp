#include "geometry/triangle_gradients.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace retarget {

Eigen::Matrix3d triangle_frame(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  Eigen::Matrix3d frame;
  frame.col(0) = b - a;
  frame.col(1) = c - a;
  const Eigen::Vector3d n = frame.col(0).cross(frame.col(1));
  const double length = n.norm();
  // n / sqrt(|n|) tends to zero with the area, so a collapsed triangle has a finite frame.
  frame.col(2) = length > 0 ? Eigen::Vector3d(n / std::sqrt(length)) : Eigen::Vector3d::Zero();
  return frame;
}

int TriangleFrames::invalid_count() const { return static_cast<int>(std::count(valid.begin(), valid.end(), char{0})); }

TriangleFrames triangle_frames(const Positions& rest, const Triangles& triangles) {
  TriangleFrames frames;
  const int count = static_cast<int>(triangles.rows());
  frames.inverse.assign(count, Eigen::Matrix3d::Zero());
  frames.valid.assign(count, 0);
  for (int t = 0; t < count; ++t) {
    const Eigen::Vector3d a = rest.row(triangles(t, 0)), b = rest.row(triangles(t, 1)), c = rest.row(triangles(t, 2));
    const Eigen::Matrix3d frame = triangle_frame(a, b, c);
    const double longest2 = std::max({(b - a).squaredNorm(), (c - a).squaredNorm(), (c - b).squaredNorm()});
    const double twice_area = frame.col(0).cross(frame.col(1)).norm();
    if (!frame.allFinite() || !(twice_area > 1e-10 * longest2)) continue;
    frames.inverse[t] = frame.inverse();
    frames.valid[t] = 1;
  }
  return frames;
}

Eigen::Matrix3d deformation_gradient(const Positions& deformed, const Triangles& triangles,
                                     const TriangleFrames& frames, int t) {
  if (!frames.valid[t]) return Eigen::Matrix3d::Identity();
  return triangle_frame(deformed.row(triangles(t, 0)), deformed.row(triangles(t, 1)), deformed.row(triangles(t, 2))) *
         frames.inverse[t];
}

Eigen::Matrix<double, 3, 4> gradient_operator(const Eigen::Matrix3d& rest_inverse) {
  // Q = [x2 - x1, x3 - x1, x4 - x1] R^-1, so row d of Q is R^-T (x2 - x1, x3 - x1, x4 - x1)[d].
  Eigen::Matrix<double, 3, 4> differences;
  differences << -1, 1, 0, 0,  //
      -1, 0, 1, 0,             //
      -1, 0, 0, 1;
  return rest_inverse.transpose() * differences;
}

}  // namespace retarget
