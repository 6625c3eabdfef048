#include "avatar/rig_welding.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.h"
#include "geometry/metrics.h"

namespace retarget {

void WeldOptions::validate(const std::string& key_path) const {
  if (!std::isfinite(relative_tolerance) || relative_tolerance <= 0)
    throw Error(key_path + ".relative_tolerance", "must be a finite number > 0");
  if (!std::isfinite(motion_tolerance) || motion_tolerance <= 0)
    throw Error(key_path + ".motion_tolerance", "must be a finite number > 0");
}

Weld weld_rig_vertices(const Rig& rig, const WeldOptions& options) {
  options.validate();
  const Positions& V = rig.neutral.vertices;
  const int n = static_cast<int>(V.rows());
  Weld weld;
  weld.representative.resize(n);
  std::iota(weld.representative.begin(), weld.representative.end(), 0);
  if (n == 0) return weld;
  const double tolerance = options.relative_tolerance * std::max(bounding_box_diagonal(V), 1e-300);
  double largest_motion = 0;
  for (const Controller& c : rig.controllers)
    if (c.offset.rows() > 0) largest_motion = std::max(largest_motion, c.offset.rowwise().norm().maxCoeff());
  const double motion_tolerance = options.motion_tolerance * std::max(largest_motion, tolerance);

  // Sort by x, then compare each vertex with the ones within `tolerance` in x after it.
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return V(a, 0) < V(b, 0) || (V(a, 0) == V(b, 0) && a < b); });
  auto same_motion = [&](int a, int b) {
    for (const Controller& c : rig.controllers)
      if ((c.offset.row(a) - c.offset.row(b)).cwiseAbs().maxCoeff() > motion_tolerance) return false;
    return true;
  };
  auto find = [&](int v) {
    while (weld.representative[v] != v) v = weld.representative[v] = weld.representative[weld.representative[v]];
    return v;
  };
  for (int i = 0; i < n; ++i) {
    const int a = order[i];
    for (int j = i + 1; j < n && V(order[j], 0) - V(a, 0) <= tolerance; ++j) {
      const int b = order[j];
      if ((V.row(a) - V.row(b)).norm() > tolerance || !same_motion(a, b)) continue;
      const int ra = find(a), rb = find(b);
      if (ra != rb) weld.representative[std::max(ra, rb)] = std::min(ra, rb);
    }
  }
  for (int v = 0; v < n; ++v) {
    weld.representative[v] = find(v);
    if (weld.representative[v] != v) ++weld.merged;
  }
  const Triangles& T = rig.neutral.triangles;
  weld.triangles.resize(T.rows(), 3);
  Eigen::Index kept = 0;
  for (Eigen::Index t = 0; t < T.rows(); ++t) {
    const int a = weld.representative[T(t, 0)], b = weld.representative[T(t, 1)], c = weld.representative[T(t, 2)];
    if (a == b || b == c || a == c) continue;
    weld.triangles.row(kept++) << a, b, c;
  }
  weld.triangles.conservativeResize(kept, 3);
  return weld;
}

}  // namespace retarget
