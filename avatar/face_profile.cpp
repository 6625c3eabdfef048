#include "avatar/face_profile.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include "geometry/metrics.h"

namespace retarget {

namespace face_profile_detail {

// A point of the cut: a vertex on the plane (key (v, v)) or an edge crossing it (key (a, b), a < b).
struct Cut {
  std::map<std::pair<int, int>, int> index;  // key -> node
  std::vector<ProfilePoint> nodes;
  std::vector<std::vector<int>> links;  // node -> the nodes it shares a triangle's cut with
};

Cut cut_triangles(const Positions& V, const Triangles& T, const MirrorPlane& plane) {
  Cut cut;
  const double eps = 1e-9 * bounding_box_diagonal(V);
  const auto side = [&](int v) {
    const double s = plane.side(V.row(v).transpose());
    return std::abs(s) <= eps ? 0.0 : s;
  };
  const auto node = [&](int a, int b) {
    const std::pair<int, int> key{std::min(a, b), std::max(a, b)};
    const auto it = cut.index.find(key);
    if (it != cut.index.end()) return it->second;
    ProfilePoint p;
    if (a == b) {
      p.position = V.row(a).transpose();
      p.vertex = a;
    } else {
      const double sa = side(a), sb = side(b), t = sa / (sa - sb);
      p.position = ((1 - t) * V.row(a) + t * V.row(b)).transpose();
      p.vertex = std::abs(sa) <= std::abs(sb) ? a : b;
    }
    cut.nodes.push_back(p);
    cut.links.emplace_back();
    cut.index[key] = static_cast<int>(cut.nodes.size()) - 1;
    return static_cast<int>(cut.nodes.size()) - 1;
  };
  for (Eigen::Index t = 0; t < T.rows(); ++t) {
    std::vector<int> here;
    for (int k = 0; k < 3; ++k) {
      const int a = T(t, k), b = T(t, (k + 1) % 3);
      const double sa = side(a), sb = side(b);
      if (sa == 0) here.push_back(node(a, a));
      if (sa != 0 && sb != 0 && (sa < 0) != (sb < 0)) here.push_back(node(a, b));
    }
    std::sort(here.begin(), here.end());
    here.erase(std::unique(here.begin(), here.end()), here.end());
    if (here.size() != 2) continue;  // a touching corner, or a triangle lying in the plane
    for (int k = 0; k < 2; ++k) {
      std::vector<int>& l = cut.links[static_cast<size_t>(here[static_cast<size_t>(k)])];
      const int other = here[static_cast<size_t>(1 - k)];
      if (std::find(l.begin(), l.end(), other) == l.end()) l.push_back(other);
    }
  }
  return cut;
}

int start_node(const Positions& V, const Cut& cut, int start) {
  const auto on = cut.index.find({start, start});
  if (on != cut.index.end()) return on->second;
  const Eigen::Vector3d at = V.row(start).transpose();
  int best = -1, best_edge = -1;
  double d = std::numeric_limits<double>::infinity(), d_edge = d;
  for (const auto& [key, n] : cut.index) {
    const double dn = (cut.nodes[static_cast<size_t>(n)].position - at).squaredNorm();
    if (dn < d) d = dn, best = n;
    if ((key.first == start || key.second == start) && dn < d_edge) d_edge = dn, best_edge = n;
  }
  return best_edge >= 0 ? best_edge : best;
}

}  // namespace face_profile_detail

std::vector<ProfilePoint> walk_profile(const Positions& V, const Triangles& triangles, const MirrorPlane& plane,
                                       int start, const Eigen::Vector3d& towards, double max_length) {
  using namespace face_profile_detail;
  const Cut cut = cut_triangles(V, triangles, plane);
  std::vector<ProfilePoint> out;
  if (cut.nodes.empty()) return out;
  int current = start_node(V, cut, start);
  std::vector<char> visited(cut.nodes.size(), 0);
  Eigen::Vector3d heading = towards;
  double length = 0;
  while (true) {
    visited[static_cast<size_t>(current)] = 1;
    const ProfilePoint& here = cut.nodes[static_cast<size_t>(current)];
    out.push_back(here);
    int next = -1;
    double best = -std::numeric_limits<double>::infinity();
    for (int n : cut.links[static_cast<size_t>(current)]) {
      if (visited[static_cast<size_t>(n)]) continue;
      const Eigen::Vector3d step = cut.nodes[static_cast<size_t>(n)].position - here.position;
      const double norm = step.norm();
      const double follow = norm > 0 ? heading.dot(step) / (norm * std::max(heading.norm(), 1e-300)) : -2;
      if (follow > best) best = follow, next = n;
    }
    if (next < 0) break;
    const Eigen::Vector3d step = cut.nodes[static_cast<size_t>(next)].position - here.position;
    length += step.norm();
    if (length > max_length) break;
    if (step.norm() > 0) heading = step;
    current = next;
  }
  return out;
}

}  // namespace retarget
