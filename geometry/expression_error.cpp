#include "geometry/expression_error.h"

#include <algorithm>

#include "geometry/metrics.h"
#include "geometry/rigid_alignment.h"

namespace retarget {

namespace {
double mean_over(const Eigen::VectorXd& d, const std::vector<int>& vertices) {
  if (vertices.empty()) return d.size() ? d.mean() : 0.0;
  double sum = 0;
  for (int v : vertices) sum += d(v);
  return sum / static_cast<double>(vertices.size());
}
}  // namespace

ExpressionError expression_error(const Positions& output, const Positions& truth, double scale,
                                 const RigFootprint& footprint) {
  const Positions aligned = rigid_alignment(output, truth).apply(output);
  const VertexError whole = vertex_error(aligned, truth, scale);
  ExpressionError e;
  e.mean = whole.mean;
  e.max = whole.max;
  e.worst_vertex = whole.worst_vertex;
  if (aligned.rows() == 0) return e;
  const Eigen::VectorXd d = (aligned - truth).rowwise().norm() * scale;
  e.moving_mean = mean_over(d, footprint.moving);
  for (const auto& [region, vertices] : footprint.regions) e.region_mean[region] = mean_over(d, vertices);
  return e;
}

void ExpressionErrorSum::add(const ExpressionError& e) {
  ++count;
  mean += e.mean;
  mean_of_max += e.max;
  max = std::max(max, e.max);
  moving_mean += e.moving_mean;
  for (const auto& [region, value] : e.region_mean) region_mean[region] += value;
}

ExpressionErrorSum ExpressionErrorSum::averaged() const {
  ExpressionErrorSum a = *this;
  if (count == 0) return a;
  a.mean /= count, a.mean_of_max /= count, a.moving_mean /= count;
  for (auto& [region, value] : a.region_mean) value /= count;
  return a;
}

}  // namespace retarget
