#include "geometry/metrics.h"

#include <string>

#include "core/error.h"

namespace retarget {

VertexError vertex_error(const Positions& a, const Positions& b, double scale) {
  if (a.rows() != b.rows())
    throw Error("vertex error",
                "vertex counts differ: " + std::to_string(a.rows()) + " and " + std::to_string(b.rows()));
  VertexError e;
  if (a.rows() == 0) return e;
  const Eigen::VectorXd d = (a - b).rowwise().norm() * scale;
  e.mean = d.mean();
  e.max = d.maxCoeff(&e.worst_vertex);
  e.rms = std::sqrt(d.squaredNorm() / d.size());
  return e;
}

namespace {
Eigen::RowVector3d centroid(const Positions& V, const std::vector<int>& indices, const char* which) {
  if (indices.empty()) throw Error(std::string(which) + " eye landmarks", "the set is empty");
  Eigen::RowVector3d c = Eigen::RowVector3d::Zero();
  for (size_t k = 0; k < indices.size(); ++k) {
    const int v = indices[k];
    if (v < 0 || v >= V.rows())
      throw Error(std::string(which) + " eye landmarks[" + std::to_string(k) + "]",
                  "vertex index " + std::to_string(v) + " is out of range (the mesh has " + std::to_string(V.rows()) +
                      " vertices)");
    c += V.row(v);
  }
  return c / static_cast<double>(indices.size());
}
}  // namespace

double millimetres_per_unit(const Positions& neutral, const EyeLandmarks& eyes) {
  const double distance = (centroid(neutral, eyes.left, "left") - centroid(neutral, eyes.right, "right")).norm();
  if (!(distance > 0)) throw Error("eye landmarks", "the left and right eye centres coincide");
  return 100.0 / distance;
}

double bounding_box_diagonal(const Positions& V) {
  if (V.rows() == 0) return 0;
  return (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
}

}  // namespace retarget
