// A profile of the face: the head's surface cut by a plane (the mirror plane, or one parallel to
// it), walked as a polyline from a vertex. Landmarks that the face's shape defines along such a
// cut are read off it: the chin on the mirror plane's profile, a brow's crest on the cut through
// the brow.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "avatar/mirror_plane.h"
#include "geometry/mesh.h"

namespace retarget {

struct ProfilePoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // on the plane, rig units
  int vertex = -1;  // the vertex it lies on, or the nearer end of the edge it crosses
};

// V: #V x 3; triangles: #T x 3 rows of V (e.g. the welded head's), the only ones cut; plane: the
// cut (MirrorPlane's normal . x = offset; its error is not used). The walk starts at the cut's
// point at `start` (a vertex on the plane), or else at the nearest cut point of an edge of
// `start`, or else at the nearest cut point; its first step is the one that best follows
// `towards` (any length), each later step the straightest continuation. It stops after
// `max_length` (rig units) of arc, at an end of the cut (a hole's rim, the mesh's border) or where
// it would meet itself. Returns the points in walking order, the start first; empty if the plane
// cuts none of the triangles.
std::vector<ProfilePoint> walk_profile(const Positions& V, const Triangles& triangles, const MirrorPlane& plane,
                                       int start, const Eigen::Vector3d& towards, double max_length);

}  // namespace retarget
