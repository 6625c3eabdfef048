// Proximity queries built once and asked many times: the closest point on a triangle
// surface (an AABB tree) and the nearest of a set of points (a k-d tree), both with an
// optional filter, which is what deformation transfer needs ("the closest point whose
// normal agrees"). CGAL stays inside closest_point.cpp.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "geometry/mesh.h"

namespace retarget {

// A point on a triangle of the surface.
struct SurfacePoint {
  int triangle = -1;                                      // index into the surface's triangles; -1: nothing qualified
  Eigen::Vector3d point = Eigen::Vector3d::Zero();        // in the surface's frame and units
  Eigen::Vector3d barycentric = Eigen::Vector3d::Zero();  // weights of the triangle's corners, sum 1
  double squared_distance = std::numeric_limits<double>::infinity();  // to the query, units^2

  bool found() const { return triangle >= 0; }
};

// Closest points on a fixed triangle surface. Queries are const and thread-safe.
class ClosestSurfacePoint {
 public:
  // vertices: #V x 3; triangles: #T x 3 indices into vertices (copied).
  // enabled: empty (all triangles) or #T flags; disabled triangles are never returned.
  ClosestSurfacePoint(const Positions& vertices, const Triangles& triangles, std::vector<char> enabled = {});
  ~ClosestSurfacePoint();
  ClosestSurfacePoint(ClosestSurfacePoint&&) noexcept;
  ClosestSurfacePoint& operator=(ClosestSurfacePoint&&) noexcept;

  // The closest point of the whole (enabled) surface to `query`.
  SurfacePoint closest(const Eigen::Vector3d& query) const;

  // The closest point on a triangle whose unit normal n (right-handed in the corner order)
  // satisfies n . direction >= min_cosine; direction: unit length. Zero-area triangles
  // never qualify. Not found (triangle -1) if no triangle qualifies.
  SurfacePoint closest(const Eigen::Vector3d& query, const Eigen::Vector3d& direction, double min_cosine) const;

  // #T x 3 unit triangle normals (zero rows for zero-area triangles).
  const Positions& triangle_normals() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Nearest neighbours among a fixed set of points. Queries are const and thread-safe.
class NearestPoints {
 public:
  // points: #P x 3 (copied); enabled: empty (all) or #P flags.
  explicit NearestPoints(const Positions& points, std::vector<char> enabled = {});
  ~NearestPoints();
  NearestPoints(NearestPoints&&) noexcept;
  NearestPoints& operator=(NearestPoints&&) noexcept;

  // The index of the nearest enabled point p with accept(p) true, visiting points in
  // order of distance and giving up past max_distance or after max_visits points
  // (whichever comes first); -1 if none qualifies.
  int nearest(const Eigen::Vector3d& query, const std::function<bool(int)>& accept,
              double max_distance = std::numeric_limits<double>::infinity(),
              int max_visits = std::numeric_limits<int>::max()) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Closest point to p on triangle (a, b, c), with the barycentric weights of a, b, c.
// Works for degenerate triangles (returns a closest point of the segments).
SurfacePoint closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c);

}  // namespace retarget
