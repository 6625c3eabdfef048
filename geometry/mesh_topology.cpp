#include "geometry/mesh_topology.h"

#include <algorithm>
#include <cstdint>
#include <numeric>

namespace retarget {

EdgeTopology edge_topology(const Triangles& triangles) {
  // Sort (edge key, opposite vertex) records once instead of hashing per edge.
  struct Record {
    int64_t key;
    int opposite;
  };
  std::vector<Record> records;
  records.reserve(3 * triangles.rows());
  for (int t = 0; t < triangles.rows(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int a = triangles(t, k), b = triangles(t, (k + 1) % 3), c = triangles(t, (k + 2) % 3);
      if (a == b) continue;  // a collapsed edge of a degenerate face carries no geometry
      const int64_t lo = std::min(a, b), hi = std::max(a, b);
      records.push_back({(lo << 32) | hi, c});
    }
  }
  std::sort(records.begin(), records.end(),
            [](const Record& x, const Record& y) { return x.key != y.key ? x.key < y.key : x.opposite < y.opposite; });
  EdgeTopology topology;
  for (size_t r = 0; r < records.size(); ++r) {
    if (r == 0 || records[r].key != records[r - 1].key) {
      if (r != 0) topology.opposite.start.push_back(static_cast<int>(topology.opposite.items.size()));
      topology.edges.push_back({static_cast<int>(records[r].key >> 32), static_cast<int>(records[r].key & 0xffffffff)});
    }
    topology.opposite.items.push_back(records[r].opposite);
  }
  if (!records.empty()) topology.opposite.start.push_back(static_cast<int>(topology.opposite.items.size()));
  return topology;
}

CompressedRows vertex_neighbors(const EdgeTopology& topology, int vertex_count) {
  CompressedRows rows;
  rows.start.assign(vertex_count + 1, 0);
  for (const auto& e : topology.edges) ++rows.start[e[0] + 1], ++rows.start[e[1] + 1];
  std::partial_sum(rows.start.begin(), rows.start.end(), rows.start.begin());
  rows.items.resize(rows.start.back());
  std::vector<int> fill(rows.start.begin(), rows.start.end() - 1);
  for (const auto& e : topology.edges) {
    rows.items[fill[e[0]]++] = e[1];
    rows.items[fill[e[1]]++] = e[0];
  }
  return rows;
}

CompressedRows vertex_triangles(const Triangles& triangles, int vertex_count) {
  CompressedRows rows;
  rows.start.assign(vertex_count + 1, 0);
  for (int t = 0; t < triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k) ++rows.start[triangles(t, k) + 1];
  std::partial_sum(rows.start.begin(), rows.start.end(), rows.start.begin());
  rows.items.resize(rows.start.back());
  std::vector<int> fill(rows.start.begin(), rows.start.end() - 1);
  for (int t = 0; t < triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k) rows.items[fill[triangles(t, k)]++] = t;
  return rows;
}

Components connected_components(const EdgeTopology& topology, int vertex_count) {
  // Union-find with path halving; components are then numbered by their lowest vertex.
  std::vector<int> parent(vertex_count);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const auto& e : topology.edges) {
    const int a = find(e[0]), b = find(e[1]);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
  Components result;
  result.component.assign(vertex_count, -1);
  std::vector<int> label(vertex_count, -1);
  for (int v = 0; v < vertex_count; ++v) {
    const int root = find(v);
    if (label[root] < 0) {
      label[root] = result.count();
      result.first_vertex.push_back(v);
    }
    result.component[v] = label[root];
  }
  return result;
}

}  // namespace retarget
