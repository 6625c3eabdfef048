// Per-vertex errors and the paper's unit convention (eye centres 10 cm apart, errors in mm).
#pragma once

#include <vector>

#include "geometry/mesh.h"

namespace retarget {

struct VertexError {
  double mean = 0;  // mean Euclidean distance per vertex
  double max = 0;   // largest distance
  double rms = 0;
  int worst_vertex = -1;  // index of the largest distance
};

// a, b: #V x 3 in one frame and unit; distances are multiplied by `scale` (e.g. mm per unit).
// Throws retarget::Error if the vertex counts differ.
VertexError vertex_error(const Positions& a, const Positions& b, double scale = 1.0);

// Eye landmarks: two vertex sets whose centroids are the eye centres.
struct EyeLandmarks {
  std::vector<int> left;
  std::vector<int> right;
};

// Millimetres per mesh unit under the paper's convention: the mesh is scaled so that the
// distance between the two eye centres (centroids of the landmark sets on `neutral`,
// #V x 3) is 10 cm. Throws retarget::Error naming the bad index or an empty set, or
// coincident eye centres.
double millimetres_per_unit(const Positions& neutral, const EyeLandmarks& eyes);

// Length of the bounding-box diagonal of V (#V x 3).
double bounding_box_diagonal(const Positions& V);

}  // namespace retarget
