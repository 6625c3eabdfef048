#include "geometry/closest_point.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Orthogonal_incremental_neighbor_search.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/Search_traits_adapter.h>
#include <CGAL/Simple_cartesian.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cassert>
#include <utility>

namespace retarget {

namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point3 = Kernel::Point_3;
using Triangle3 = Kernel::Triangle_3;
using TriangleIterator = std::vector<Triangle3>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>;
using AabbTraits = CGAL::AABB_traits<Kernel, Primitive>;
using AabbTree = CGAL::AABB_tree<AabbTraits>;
using AabbNode = CGAL::AABB_node<AabbTraits>;

Point3 to_point(const Eigen::Vector3d& v) { return Point3(v.x(), v.y(), v.z()); }

double box_squared_distance(const CGAL::Bbox_3& box, const Eigen::Vector3d& p) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double below = box.min(k) - p[k], above = p[k] - box.max(k);
    if (below > 0)
      d2 += below * below;
    else if (above > 0)
      d2 += above * above;
  }
  return d2;
}

SurfacePoint closest_on_segment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double s = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  SurfacePoint out;
  out.triangle = 0;
  out.point = a + s * ab;
  out.barycentric = Eigen::Vector3d(1 - s, s, 0);
  out.squared_distance = (p - out.point).squaredNorm();
  return out;
}

}  // namespace

SurfacePoint closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, bc = c - b;
  const double longest2 = std::max({ab.squaredNorm(), ac.squaredNorm(), bc.squaredNorm()});
  // Below this the region tests of the triangle case divide by (near) zero; the closest
  // point of a sliver is then the closest point of its three edges.
  if (ab.cross(ac).squaredNorm() <= 1e-24 * longest2 * longest2) {
    SurfacePoint best = closest_on_segment(p, a, b);
    SurfacePoint s2 = closest_on_segment(p, a, c);
    s2.barycentric = Eigen::Vector3d(s2.barycentric[0], 0, s2.barycentric[1]);
    SurfacePoint s3 = closest_on_segment(p, b, c);
    s3.barycentric = Eigen::Vector3d(0, s3.barycentric[0], s3.barycentric[1]);
    if (s2.squared_distance < best.squared_distance) best = s2;
    if (s3.squared_distance < best.squared_distance) best = s3;
    return best;
  }
  // Voronoi regions of the corners, edges and face (Ericson, Real-Time Collision
  // Detection, 5.1.5); every division below has a positive denominator for a proper triangle.
  Eigen::Vector3d w;
  const Eigen::Vector3d ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
  if (d1 <= 0 && d2 <= 0) {
    w = {1, 0, 0};
  } else if (d3 >= 0 && d4 <= d3) {
    w = {0, 1, 0};
  } else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    w = {1 - v, v, 0};
  } else if (d6 >= 0 && d5 <= d6) {
    w = {0, 0, 1};
  } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double t = d2 / (d2 - d6);
    w = {1 - t, 0, t};
  } else if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    w = {0, 1 - t, t};
  } else {
    const double inv = 1.0 / (va + vb + vc);
    const double v = vb * inv, t = vc * inv;
    w = {1 - v - t, v, t};
  }
  SurfacePoint out;
  out.triangle = 0;
  out.barycentric = w;
  out.point = w[0] * a + w[1] * b + w[2] * c;
  out.squared_distance = (p - out.point).squaredNorm();
  return out;
}

// ---------------------------------------------------------------------------------------

struct ClosestSurfacePoint::Impl {
  Positions vertices;
  Triangles triangles;
  Positions normals;
  std::vector<Triangle3> cgal_triangles;  // enabled triangles only
  std::vector<int> triangle_of;           // index in cgal_triangles -> mesh triangle
  AabbTree tree;

  // Best-first descent (nearer boxes first) with a per-primitive filter: CGAL's own
  // closest_point() cannot skip primitives, and a filtered query is what we need.
  struct Traversal {
    using Priority = double;
    const Impl& impl;
    Eigen::Vector3d query;
    const Eigen::Vector3d* direction;  // null: no filter
    double min_cosine;
    SurfacePoint best;

    bool go_further() const { return true; }
    void intersection(const Point3&, const Primitive& primitive) {
      const int t = impl.triangle_of[primitive.id() - impl.cgal_triangles.begin()];
      if (direction) {
        const Eigen::Vector3d n = impl.normals.row(t);
        if (n.squaredNorm() == 0 || n.dot(*direction) < min_cosine) return;
      }
      const auto& tri = impl.triangles.row(t);
      SurfacePoint candidate = closest_point_on_triangle(query, impl.vertices.row(tri[0]), impl.vertices.row(tri[1]),
                                                         impl.vertices.row(tri[2]));
      if (candidate.squared_distance < best.squared_distance) {
        candidate.triangle = t;
        best = candidate;
      }
    }
    bool do_intersect(const Point3&, const AabbNode& node) const {
      return box_squared_distance(node.bbox(), query) < best.squared_distance;
    }
    std::pair<bool, double> do_intersect_with_priority(const Point3&, const AabbNode& node) const {
      const double d2 = box_squared_distance(node.bbox(), query);
      return {d2 < best.squared_distance, -d2};
    }
  };

  SurfacePoint run(const Eigen::Vector3d& query, const Eigen::Vector3d* direction, double min_cosine) const {
    Traversal traversal{*this, query, direction, min_cosine, SurfacePoint{}};
    tree.traversal_with_priority(to_point(query), traversal);
    return traversal.best;
  }
};

ClosestSurfacePoint::ClosestSurfacePoint(const Positions& vertices, const Triangles& triangles,
                                         std::vector<char> enabled)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  assert(enabled.empty() || static_cast<int>(enabled.size()) == triangles.rows());
  m.vertices = vertices;
  m.triangles = triangles;
  m.normals.setZero(triangles.rows(), 3);
  for (int t = 0; t < triangles.rows(); ++t) {
    const Eigen::Vector3d a = vertices.row(triangles(t, 0)), b = vertices.row(triangles(t, 1)),
                          c = vertices.row(triangles(t, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() > 0) m.normals.row(t) = n.normalized();
    if (!enabled.empty() && !enabled[t]) continue;
    m.cgal_triangles.emplace_back(to_point(a), to_point(b), to_point(c));
    m.triangle_of.push_back(t);
  }
  m.tree.insert(m.cgal_triangles.cbegin(), m.cgal_triangles.cend());
  // Built here, not lazily on the first query, so that concurrent queries are safe.
  if (!m.cgal_triangles.empty()) m.tree.build();
}

ClosestSurfacePoint::~ClosestSurfacePoint() = default;
ClosestSurfacePoint::ClosestSurfacePoint(ClosestSurfacePoint&&) noexcept = default;
ClosestSurfacePoint& ClosestSurfacePoint::operator=(ClosestSurfacePoint&&) noexcept = default;

SurfacePoint ClosestSurfacePoint::closest(const Eigen::Vector3d& query) const { return impl_->run(query, nullptr, 0); }

SurfacePoint ClosestSurfacePoint::closest(const Eigen::Vector3d& query, const Eigen::Vector3d& direction,
                                          double min_cosine) const {
  return impl_->run(query, &direction, min_cosine);
}

const Positions& ClosestSurfacePoint::triangle_normals() const { return impl_->normals; }

// ---------------------------------------------------------------------------------------

namespace {

// The k-d tree stores point indices; coordinates are read through a property map.
struct IndexToPoint {
  using key_type = int;
  using value_type = Point3;
  using reference = const Point3&;
  using category = boost::readable_property_map_tag;
  const std::vector<Point3>* points = nullptr;
  friend reference get(const IndexToPoint& map, int i) { return (*map.points)[i]; }
};

using SearchBase = CGAL::Search_traits_3<Kernel>;
using SearchTraits = CGAL::Search_traits_adapter<int, IndexToPoint, SearchBase>;
using IncrementalSearch = CGAL::Orthogonal_incremental_neighbor_search<SearchTraits>;
using KdTree = IncrementalSearch::Tree;

}  // namespace

struct NearestPoints::Impl {
  std::vector<Point3> points;
  std::unique_ptr<KdTree> tree;
};

NearestPoints::NearestPoints(const Positions& points, std::vector<char> enabled) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  assert(enabled.empty() || static_cast<int>(enabled.size()) == points.rows());
  m.points.reserve(points.rows());
  std::vector<int> ids;
  for (int i = 0; i < points.rows(); ++i) {
    m.points.emplace_back(points(i, 0), points(i, 1), points(i, 2));
    if (enabled.empty() || enabled[i]) ids.push_back(i);
  }
  IndexToPoint map;
  map.points = &m.points;
  m.tree = std::make_unique<KdTree>(ids.begin(), ids.end(), KdTree::Splitter(), SearchTraits(map));
  // Built here, not lazily on the first query, so that concurrent queries are safe.
  m.tree->build();
}

NearestPoints::~NearestPoints() = default;
NearestPoints::NearestPoints(NearestPoints&&) noexcept = default;
NearestPoints& NearestPoints::operator=(NearestPoints&&) noexcept = default;

int NearestPoints::nearest(const Eigen::Vector3d& query, const std::function<bool(int)>& accept, double max_distance,
                           int max_visits) const {
  const Impl& m = *impl_;
  if (m.tree->size() == 0) return -1;
  IndexToPoint map;
  map.points = &m.points;
  IncrementalSearch search(*m.tree, to_point(query), 0.0, true, IncrementalSearch::Distance(map));
  const double max_d2 = max_distance * max_distance;
  int visits = 0;
  for (auto it = search.begin(); it != search.end() && visits < max_visits; ++it, ++visits) {
    if (it->second > max_d2) break;
    if (accept(it->first)) return it->first;
  }
  return -1;
}

}  // namespace retarget
