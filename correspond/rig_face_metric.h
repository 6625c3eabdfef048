// How far apart two rig expressions' faces are, as a metric on controller weights: the rig is
// linear in its controllers, so |w - v|^2_G with G the Gram matrix of the controllers' offsets
// over the vertices the rig moves is the squared distance between the two faces (scaled).
#pragma once

#include <Eigen/Core>

#include "data/dataset.h"
#include "geometry/rig.h"

namespace retarget {

// C x C, scaled to a mean diagonal of 1 (units comparable to squared weights); the vertices
// that move more than 0.1 mm at some controller's extreme count (`avatar`'s eye distance gives
// the millimetres; without eye landmarks, 0.1 avatar units). The identity for a rig that moves
// nothing.
Eigen::MatrixXd rig_face_metric(const Rig& rig, const Dataset& avatar);

// The controllers' ranges of `rig`, C each.
Eigen::VectorXd rig_lower(const Rig& rig);
Eigen::VectorXd rig_upper(const Rig& rig);

}  // namespace retarget
