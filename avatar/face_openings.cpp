#include "avatar/face_openings.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>
#include <unordered_set>

#include "avatar/boundary_loops.h"
#include "core/error.h"
#include "geometry/mesh_topology.h"
#include "geometry/metrics.h"
#include "geometry/rigid_alignment.h"

namespace retarget {

void FaceOpeningOptions::validate(const std::string& key_path) const {
  const auto positive = [&](double value, const char* field) {
    if (!std::isfinite(value) || value <= 0) throw Error(key_path + "." + field, "must be a finite number > 0");
  };
  positive(slit_radius, "slit_radius");
  positive(slit_parting, "slit_parting");
  positive(slit_ratio, "slit_ratio");
  positive(max_hole_size, "max_hole_size");
  positive(min_hole_share, "min_hole_share");
  if (min_slit_pairs < 1) throw Error(key_path + ".min_slit_pairs", "must be at least 1");
}

HeadAndParts split_head_and_parts(const Rig& rig, const Weld& weld) {
  const int n = rig.neutral.vertex_count();
  const Components components = connected_components(edge_topology(weld.triangles), n);
  std::vector<int> size(static_cast<size_t>(components.count()), 0);
  std::vector<char> used(static_cast<size_t>(n), 0);
  for (Eigen::Index t = 0; t < weld.triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k) used[static_cast<size_t>(weld.triangles(t, k))] = 1;
  for (int v = 0; v < n; ++v)
    if (used[static_cast<size_t>(v)]) ++size[static_cast<size_t>(components.component[static_cast<size_t>(v)])];
  HeadAndParts out;
  out.head.assign(static_cast<size_t>(n), 0);
  if (n == 0) return out;
  const int head = static_cast<int>(std::max_element(size.begin(), size.end()) - size.begin());
  std::vector<std::vector<int>> members(static_cast<size_t>(components.count()));
  for (int v = 0; v < n; ++v) {
    if (!used[static_cast<size_t>(v)]) continue;
    const int c = components.component[static_cast<size_t>(v)];
    if (c == head)
      out.head[static_cast<size_t>(v)] = 1;
    else
      members[static_cast<size_t>(c)].push_back(v);
  }
  for (std::vector<int>& m : members)
    if (!m.empty()) out.parts.push_back(std::move(m));
  return out;
}

namespace openings_detail {

Eigen::Vector3d centroid_of(const Positions& V, const std::vector<int>& vertices) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int v : vertices) c += V.row(v).transpose();
  return vertices.empty() ? c : Eigen::Vector3d(c / static_cast<double>(vertices.size()));
}

double size_of(const Positions& V, const std::vector<int>& vertices) {
  if (vertices.empty()) return 0;
  Eigen::Vector3d lo = V.row(vertices[0]).transpose(), hi = lo;
  for (int v : vertices) {
    lo = lo.cwiseMin(V.row(v).transpose());
    hi = hi.cwiseMax(V.row(v).transpose());
  }
  return (hi - lo).norm();
}

// RMS of the rim's motion under `offset` once the rim's best rigid motion is taken out.
double non_rigid_motion(const Positions& V, const Positions& offset, const std::vector<int>& rim) {
  Positions from(static_cast<Eigen::Index>(rim.size()), 3), to(static_cast<Eigen::Index>(rim.size()), 3);
  for (size_t i = 0; i < rim.size(); ++i) {
    from.row(static_cast<Eigen::Index>(i)) = V.row(rim[i]);
    to.row(static_cast<Eigen::Index>(i)) = V.row(rim[i]) + offset.row(rim[i]);
  }
  const RigidTransform fit = rigid_alignment(from, to);
  return std::sqrt((fit.apply(from) - to).rowwise().squaredNorm().mean());
}

// Pairs of head vertices closer than `radius` at rest (i < j), through a uniform grid.
std::vector<std::array<int, 2>> close_pairs(const Positions& V, const std::vector<int>& vertices, double radius) {
  struct CellHash {
    size_t operator()(const std::array<long long, 3>& c) const {
      return static_cast<size_t>(c[0] * 73856093LL ^ c[1] * 19349663LL ^ c[2] * 83492791LL);
    }
  };
  std::unordered_map<std::array<long long, 3>, std::vector<int>, CellHash> grid;
  const auto cell = [&](int v) {
    return std::array<long long, 3>{static_cast<long long>(std::floor(V(v, 0) / radius)),
                                    static_cast<long long>(std::floor(V(v, 1) / radius)),
                                    static_cast<long long>(std::floor(V(v, 2) / radius))};
  };
  for (int v : vertices) grid[cell(v)].push_back(v);
  std::vector<std::array<int, 2>> pairs;
  for (int v : vertices) {
    const std::array<long long, 3> c = cell(v);
    for (long long dx = -1; dx <= 1; ++dx)
      for (long long dy = -1; dy <= 1; ++dy)
        for (long long dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == grid.end()) continue;
          for (int u : it->second)
            if (u > v && (V.row(u) - V.row(v)).norm() < radius) pairs.push_back({v, u});
        }
  }
  return pairs;
}

int find_root(std::vector<int>& parent, int v) {
  while (parent[static_cast<size_t>(v)] != v)
    v = parent[static_cast<size_t>(v)] = parent[static_cast<size_t>(parent[static_cast<size_t>(v)])];
  return v;
}

}  // namespace openings_detail

std::vector<FaceOpening> find_face_openings(const Rig& rig, const Weld& weld, const std::vector<char>& head,
                                            const FaceOpeningOptions& options) {
  using namespace openings_detail;
  options.validate();
  const Positions& V = rig.neutral.vertices;
  const int n = rig.neutral.vertex_count();
  if (static_cast<int>(head.size()) != n)
    throw Error("face openings",
                "head flags: " + std::to_string(head.size()) + " entries for " + std::to_string(n) + " vertices");
  std::vector<int> head_vertices;
  for (int v = 0; v < n; ++v)
    if (head[static_cast<size_t>(v)]) head_vertices.push_back(v);
  std::vector<FaceOpening> openings;
  if (head_vertices.size() < 4) return openings;
  const double diagonal = size_of(V, head_vertices);

  // Holes: boundary loops of the head.
  Triangles head_triangles(weld.triangles.rows(), 3);
  Eigen::Index kept = 0;
  for (Eigen::Index t = 0; t < weld.triangles.rows(); ++t)
    if (head[static_cast<size_t>(weld.triangles(t, 0))]) head_triangles.row(kept++) = weld.triangles.row(t);
  head_triangles.conservativeResize(kept, 3);
  for (std::vector<int>& rim : boundary_loops(head_triangles)) {
    if (rim.size() < 3) continue;
    FaceOpening hole;
    hole.kind = FaceOpening::Kind::hole;
    hole.centre = centroid_of(V, rim);
    hole.size = size_of(V, rim);
    if (hole.size > options.max_hole_size * diagonal) continue;
    for (int c = 0; c < rig.controller_count(); ++c) {
      const Positions& D = rig.controllers[static_cast<size_t>(c)].offset;
      const double largest = D.rows() > 0 ? D.rowwise().norm().maxCoeff() : 0;
      const double motion = non_rigid_motion(V, D, rim);
      if (largest > 0 && motion >= options.min_hole_share * largest && motion > hole.opening) {
        hole.opening = motion;
        hole.controller = c;
      }
    }
    hole.vertices = std::move(rim);
    openings.push_back(std::move(hole));
  }

  // Slits: close pairs that part, per controller.
  std::unordered_set<long long> edges;
  for (Eigen::Index t = 0; t < head_triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      const long long a = head_triangles(t, k), b = head_triangles(t, (k + 1) % 3);
      edges.insert(std::min(a, b) * n + std::max(a, b));
    }
  std::vector<int> representatives;
  for (int v : head_vertices)
    if (weld.representative[static_cast<size_t>(v)] == v) representatives.push_back(v);
  std::vector<std::array<int, 2>> candidates;
  for (const std::array<int, 2>& p : close_pairs(V, representatives, options.slit_radius * diagonal))
    if (!edges.count(static_cast<long long>(p[0]) * n + p[1])) candidates.push_back(p);
  std::vector<int> parent(static_cast<size_t>(n));
  for (int c = 0; c < rig.controller_count(); ++c) {
    const Positions& D = rig.controllers[static_cast<size_t>(c)].offset;
    const double largest = D.rows() > 0 ? D.rowwise().norm().maxCoeff() : 0;
    if (!(largest > 0)) continue;
    std::vector<std::array<int, 2>> parting;
    std::vector<double> amount;
    for (const std::array<int, 2>& p : candidates) {
      const double apart = (D.row(p[0]) - D.row(p[1])).norm();
      const double rest = (V.row(p[0]) - V.row(p[1])).norm();
      if (apart > options.slit_parting * largest && apart > options.slit_ratio * rest) {
        parting.push_back(p);
        amount.push_back(apart);
      }
    }
    if (parting.empty()) continue;
    // Clusters: pairs joined through shared vertices or mesh edges between their vertices.
    std::iota(parent.begin(), parent.end(), 0);
    std::unordered_set<int> members;
    for (const std::array<int, 2>& p : parting) {
      members.insert(p[0]);
      members.insert(p[1]);
      parent[static_cast<size_t>(find_root(parent, p[0]))] = find_root(parent, p[1]);
    }
    for (Eigen::Index t = 0; t < head_triangles.rows(); ++t)
      for (int k = 0; k < 3; ++k) {
        const int a = head_triangles(t, k), b = head_triangles(t, (k + 1) % 3);
        if (members.count(a) && members.count(b))
          parent[static_cast<size_t>(find_root(parent, a))] = find_root(parent, b);
      }
    std::unordered_map<int, size_t> cluster_of;
    std::vector<FaceOpening> clusters;
    std::vector<std::vector<double>> cluster_amounts;
    for (size_t i = 0; i < parting.size(); ++i) {
      const int root = find_root(parent, parting[i][0]);
      auto [it, fresh] = cluster_of.emplace(root, clusters.size());
      if (fresh) {
        clusters.emplace_back();
        cluster_amounts.emplace_back();
      }
      clusters[it->second].pairs.push_back(parting[i]);
      cluster_amounts[it->second].push_back(amount[i]);
    }
    for (size_t k = 0; k < clusters.size(); ++k) {
      FaceOpening& slit = clusters[k];
      if (static_cast<int>(slit.pairs.size()) < options.min_slit_pairs) continue;
      slit.kind = FaceOpening::Kind::slit;
      slit.controller = c;
      for (const std::array<int, 2>& p : slit.pairs) {
        slit.vertices.push_back(p[0]);
        slit.vertices.push_back(p[1]);
      }
      std::sort(slit.vertices.begin(), slit.vertices.end());
      slit.vertices.erase(std::unique(slit.vertices.begin(), slit.vertices.end()), slit.vertices.end());
      std::vector<double>& a = cluster_amounts[k];
      std::nth_element(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(a.size() / 2), a.end());
      slit.opening = a[a.size() / 2];
      slit.centre = centroid_of(V, slit.vertices);
      slit.size = size_of(V, slit.vertices);
      openings.push_back(std::move(slit));
    }
  }
  return openings;
}

}  // namespace retarget
