#include "avatar/boundary_loops.h"

#include <algorithm>
#include <map>
#include <utility>

namespace retarget {

std::vector<std::vector<int>> boundary_loops(const Triangles& triangles) {
  // Count each undirected edge; keep the direction it has in its triangle.
  std::map<std::pair<int, int>, int> count;
  for (Eigen::Index t = 0; t < triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = triangles(t, k), b = triangles(t, (k + 1) % 3);
      ++count[{std::min(a, b), std::max(a, b)}];
    }
  std::multimap<int, int> next;  // boundary edges a -> b in triangle order
  for (Eigen::Index t = 0; t < triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = triangles(t, k), b = triangles(t, (k + 1) % 3);
      if (count[{std::min(a, b), std::max(a, b)}] == 1) next.emplace(a, b);
    }
  std::vector<std::vector<int>> loops;
  while (!next.empty()) {
    auto it = next.begin();
    const int start = it->first;
    std::vector<int> loop{start};
    int at = it->second;
    next.erase(it);
    while (at != start) {
      loop.push_back(at);
      auto step = next.find(at);
      if (step == next.end()) break;  // an open chain (non-manifold rim): keep what was walked
      at = step->second;
      next.erase(step);
    }
    loops.push_back(std::move(loop));
  }
  std::sort(loops.begin(), loops.end(), [](const std::vector<int>& a, const std::vector<int>& b) {
    return a.size() != b.size() ? a.size() > b.size() : a.front() < b.front();
  });
  return loops;
}

}  // namespace retarget
