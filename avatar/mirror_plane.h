// The plane a face is mirror-symmetric about: found from the points alone (coordinate axes and
// principal axes as starting guesses, each refined by iterated closest points of the mirrored
// points), so a head exported in any orientation is handled.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "geometry/mesh.h"

namespace retarget {

struct MirrorPlane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitX();  // unit length
  double offset = 0;                                  // the plane: normal . x = offset (units)
  double error = 0;  // median distance of a mirrored point to the nearest point, / bounding-box diagonal

  double side(const Eigen::Vector3d& p) const { return normal.dot(p) - offset; }  // signed distance
  Eigen::Vector3d reflect(const Eigen::Vector3d& p) const { return p - 2 * side(p) * normal; }
};

struct MirrorPlaneOptions {
  int samples = 1500;   // points used for the fit (an even spread of the input); >= 10
  int iterations = 12;  // refinements per starting guess; >= 1

  // Throws retarget::Error naming `key_path`.<field> for a value out of range.
  void validate(const std::string& key_path = "mirror") const;
};

// points: #P x 3 (P >= 4; e.g. the welded vertices of the head). Returns the best plane over the
// starting guesses (smallest error). Throws retarget::Error for fewer than 4 points or
// coincident points (no extent).
MirrorPlane find_mirror_plane(const Positions& points, const MirrorPlaneOptions& options = {});

}  // namespace retarget
