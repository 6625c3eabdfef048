#include "avatar/mirror_plane.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "geometry/closest_point.h"
#include "geometry/metrics.h"

namespace retarget {

void MirrorPlaneOptions::validate(const std::string& key_path) const {
  if (samples < 10) throw Error(key_path + ".samples", "must be at least 10 (got " + std::to_string(samples) + ")");
  if (iterations < 1)
    throw Error(key_path + ".iterations", "must be at least 1 (got " + std::to_string(iterations) + ")");
}

namespace mirror_detail {

double median_of(std::vector<double> values) {
  if (values.empty()) return 0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// Refines `plane` by pairing each sample with the point nearest its mirror image and fitting
// the plane that swaps the pairs (normal along the pairs' differences, offset through their
// midpoints), dropping pairs beyond three times the median distance.
MirrorPlane refine(const Positions& points, const std::vector<int>& samples, const NearestPoints& nearest,
                   MirrorPlane plane, int iterations, double diagonal) {
  const auto any = [](int) { return true; };
  std::vector<double> distance(samples.size());
  std::vector<int> partner(samples.size());
  for (int iteration = 0; iteration <= iterations; ++iteration) {
    for (size_t s = 0; s < samples.size(); ++s) {
      const Eigen::Vector3d p = points.row(samples[s]);
      const Eigen::Vector3d q = plane.reflect(p);
      partner[s] = nearest.nearest(q, any);
      distance[s] = (points.row(partner[s]).transpose() - q).norm();
    }
    plane.error = median_of(distance) / diagonal;
    if (iteration == iterations) break;
    const double cut = 3 * median_of(distance) + 1e-12 * diagonal;
    Eigen::Vector3d direction = Eigen::Vector3d::Zero();
    int used = 0;
    for (size_t s = 0; s < samples.size(); ++s) {
      if (distance[s] > cut) continue;
      const Eigen::Vector3d p = points.row(samples[s]), m = points.row(partner[s]);
      Eigen::Vector3d d = p - m;
      if (d.dot(plane.normal) < 0) d = -d;
      direction += d;
      ++used;
    }
    if (used == 0 || direction.norm() < 1e-12 * diagonal) break;
    const Eigen::Vector3d normal = direction.normalized();
    // The offset through the midpoints, measured along the new normal.
    double new_offset = 0;
    for (size_t s = 0; s < samples.size(); ++s)
      if (distance[s] <= cut) new_offset += normal.dot(0.5 * (points.row(samples[s]) + points.row(partner[s])));
    plane.normal = normal;
    plane.offset = new_offset / used;
  }
  return plane;
}

}  // namespace mirror_detail

MirrorPlane find_mirror_plane(const Positions& points, const MirrorPlaneOptions& options) {
  options.validate();
  const Eigen::Index n = points.rows();
  if (n < 4) throw Error("mirror plane", "needs at least 4 points (got " + std::to_string(n) + ")");
  const double diagonal = bounding_box_diagonal(points);
  if (!(diagonal > 0)) throw Error("mirror plane", "the points all coincide: there is no shape to mirror");
  std::vector<int> samples;
  const Eigen::Index step = std::max<Eigen::Index>(1, n / options.samples);
  for (Eigen::Index i = 0; i < n; i += step) samples.push_back(static_cast<int>(i));
  const NearestPoints nearest(points);

  const Eigen::Vector3d centroid = points.colwise().mean().transpose();
  const Eigen::MatrixXd centred = points.rowwise() - centroid.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> pca(centred.transpose() * centred);
  std::vector<Eigen::Vector3d> guesses = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
  for (int k = 0; k < 3; ++k) guesses.push_back(pca.eigenvectors().col(k).normalized());

  MirrorPlane best;
  best.error = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& normal : guesses) {
    MirrorPlane start;
    start.normal = normal;
    std::vector<double> along(static_cast<size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i) along[static_cast<size_t>(i)] = normal.dot(points.row(i).transpose());
    start.offset = mirror_detail::median_of(along);
    const MirrorPlane refined = mirror_detail::refine(points, samples, nearest, start, options.iterations, diagonal);
    if (refined.error < best.error) best = refined;
  }
  return best;
}

}  // namespace retarget
