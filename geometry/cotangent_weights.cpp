#include "geometry/cotangent_weights.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace retarget {

EdgeWeighting parse_edge_weighting(const std::string& text, const std::string& where) {
  if (text == "cotangent") return EdgeWeighting::cotangent;
  if (text == "uniform") return EdgeWeighting::uniform;
  throw Error(where, "expected \"cotangent\" or \"uniform\", got \"" + text + "\"");
}

const char* to_string(EdgeWeighting weighting) {
  return weighting == EdgeWeighting::cotangent ? "cotangent" : "uniform";
}

namespace {
constexpr double kCosineLimit = 0.99;
constexpr double kFloorFraction = 1e-4;

// Cotangent of the angle at `apex` between the rays to a and b, from a clamped cosine.
double clamped_cotangent(const Eigen::Vector3d& apex, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d u = a - apex, v = b - apex;
  const double lengths = u.norm() * v.norm();
  if (!(lengths > 0)) return 0;  // a collapsed triangle says nothing about this edge
  const double c = std::clamp(u.dot(v) / lengths, -kCosineLimit, kCosineLimit);
  return c / std::sqrt(1 - c * c);
}
}  // namespace

Eigen::VectorXd edge_weights(const Positions& V, const EdgeTopology& topology, EdgeWeighting weighting) {
  const int edge_count = static_cast<int>(topology.edges.size());
  Eigen::VectorXd w = Eigen::VectorXd::Ones(edge_count);
  if (weighting == EdgeWeighting::uniform || edge_count == 0) return w;
  for (int e = 0; e < edge_count; ++e) {
    const Eigen::Vector3d p = V.row(topology.edges[e][0]).transpose();
    const Eigen::Vector3d q = V.row(topology.edges[e][1]).transpose();
    double sum = 0;
    for (int k = topology.opposite.start[e]; k < topology.opposite.start[e + 1]; ++k)
      sum += clamped_cotangent(V.row(topology.opposite.items[k]).transpose(), p, q);
    if (topology.opposite.size(e) == 1) sum *= 2;
    w[e] = std::max(sum, 0.0);
  }
  const double floor = kFloorFraction * std::max(w.mean(), 1e-300);
  w = w.cwiseMax(floor);
  return w;
}

}  // namespace retarget
