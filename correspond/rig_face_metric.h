// How far apart two rig expressions' faces are, as a metric on controller weights: the rig is
// linear in its controllers, so |w - v|^2_G with G the Gram matrix of the controllers' offsets
// over the vertices the rig moves is the squared distance between the two faces (scaled).
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

#include "data/dataset.h"
#include "geometry/rig.h"

namespace retarget {

// C x C, scaled to a mean diagonal of 1 (units comparable to squared weights); the vertices
// that move more than 0.1 mm at some controller's extreme count (`avatar`'s eye distance gives
// the millimetres; without eye landmarks, 0.1 avatar units). The identity for a rig that moves
// nothing.
Eigen::MatrixXd rig_face_metric(const Rig& rig, const Dataset& avatar);

// The same as people compare faces to a human expression: part by part, over the face regions
// (mouth, eyes, brows: geometry/rig_footprint.h) that the controllers of `rows` stand for (a
// controller table's reading: controller -> the human shapes it means; a controller with none
// has no region), each region's squared distance averaged over its vertices and the regions
// weighted equally. A part with no human counterpart (a fox's ears) is not compared, however
// many vertices it moves. Without any region: rig_face_metric(rig, avatar).
Eigen::MatrixXd rig_face_metric(const Rig& rig, const Dataset& avatar,
                                const std::map<std::string, std::vector<std::string>>& rows);

// The controllers' ranges of `rig`, C each.
Eigen::VectorXd rig_lower(const Rig& rig);
Eigen::VectorXd rig_upper(const Rig& rig);

}  // namespace retarget
