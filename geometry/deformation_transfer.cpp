#include "geometry/deformation_transfer.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <numeric>
#include <optional>
#include <string>
#include <tuple>
#include <utility>

#include "core/error.h"
#include "geometry/closest_point.h"
#include "geometry/sparse_cholesky.h"
#include "geometry/triangle_gradients.h"

namespace retarget {

namespace {

using Clock = std::chrono::steady_clock;
using Triplet = Eigen::Triplet<double>;
using Operator = Eigen::Matrix<double, 3, 4>;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

std::string describe(const Mesh& mesh, const char* role) {
  return mesh.source.empty() ? std::string(role) : fmt::format("{} ({})", role, mesh.source);
}

// Weights are dimensionless; distances are divided by this many source edge lengths.
constexpr double kAnchorWeight = 1e-6;
// Target triangles with nothing compatible within the radius look this far down the list
// of nearest source triangles before falling back to the identity.
constexpr int kFallbackVisits = 64;

// The source is placed over the target by p -> scale * rotation * p + translation.
struct Similarity {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  double scale = 1;
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Positions apply(const Positions& points) const {
    Positions out = (scale * points * rotation.transpose()).rowwise() + translation.transpose();
    return out;
  }
};

Similarity prealign(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to,
                    DeformationTransferOptions::Prealignment mode) {
  using Mode = DeformationTransferOptions::Prealignment;
  Similarity out;
  if (mode == Mode::none) return out;
  const Eigen::Vector3d from_mean = from.rowwise().mean(), to_mean = to.rowwise().mean();
  const Eigen::Matrix3Xd from_centred = from.colwise() - from_mean;
  const Eigen::Matrix3Xd to_centred = to.colwise() - to_mean;
  const double from_spread = from_centred.norm(), to_spread = to_centred.norm();
  if (!(from_spread > 0) || !(to_spread > 0))
    throw Error("deformation transfer landmarks",
                "all source (or all target) landmarks are at one point; the meshes cannot be "
                "aligned by them");
  if (mode == Mode::similarity) {
    const Eigen::JacobiSVD<Eigen::Matrix3Xd> svd(from_centred);
    const Eigen::Vector3d sv = svd.singularValues();
    if (!(sv[1] > 1e-6 * sv[0]))
      throw Error("deformation transfer landmarks",
                  "the source landmarks lie on one line, so they do not fix a rotation; add "
                  "landmarks off that line or set prealignment to translation_scale");
    const Eigen::Matrix4d T = Eigen::umeyama(from, to, true);
    out.scale = T.block<3, 1>(0, 0).norm();
    out.rotation = T.topLeftCorner<3, 3>() / out.scale;
    out.translation = T.topRightCorner<3, 1>();
  } else {
    out.scale = to_spread / from_spread;
    out.translation = to_mean - out.scale * from_mean;
  }
  return out;
}

double mean_edge_length(const Positions& V, const Triangles& F) {
  double sum = 0;
  for (int t = 0; t < F.rows(); ++t)
    for (int k = 0; k < 3; ++k) sum += (V.row(F(t, k)) - V.row(F(t, (k + 1) % 3))).norm();
  return F.rows() > 0 ? sum / (3.0 * F.rows()) : 0.0;
}

// Area-weighted unit vertex normals over the enabled triangles (zero where none).
Positions vertex_normals(const Positions& V, const Triangles& F, const std::vector<char>& enabled) {
  Positions normals = Positions::Zero(V.rows(), 3);
  for (int t = 0; t < F.rows(); ++t) {
    if (!enabled[t]) continue;
    const Eigen::RowVector3d n = (V.row(F(t, 1)) - V.row(F(t, 0))).cross(V.row(F(t, 2)) - V.row(F(t, 0)));
    for (int k = 0; k < 3; ++k) normals.row(F(t, k)) += n;
  }
  for (int i = 0; i < normals.rows(); ++i) {
    const double length = normals.row(i).norm();
    if (length > 0) normals.row(i) /= length;
  }
  return normals;
}

Positions triangle_centroids(const Positions& V, const Triangles& F) {
  Positions c(F.rows(), 3);
  for (int t = 0; t < F.rows(); ++t) c.row(t) = (V.row(F(t, 0)) + V.row(F(t, 1)) + V.row(F(t, 2))) / 3.0;
  return c;
}

Positions triangle_normals(const Positions& V, const Triangles& F) {
  Positions n = Positions::Zero(F.rows(), 3);
  for (int t = 0; t < F.rows(); ++t) {
    const Eigen::RowVector3d c = (V.row(F(t, 1)) - V.row(F(t, 0))).cross(V.row(F(t, 2)) - V.row(F(t, 0)));
    if (c.norm() > 0) n.row(t) = c.normalized();
  }
  return n;
}

// Connected parts through the enabled triangles; a vertex in none is its own part.
// Returns a part label per vertex, parts numbered by their lowest vertex.
std::vector<int> components(int vertex_count, const Triangles& F, const std::vector<char>& enabled, int& count) {
  std::vector<int> parent(vertex_count);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (int t = 0; t < F.rows(); ++t) {
    if (!enabled[t]) continue;
    for (int k = 1; k < 3; ++k) {
      const int a = find(F(t, 0)), b = find(F(t, k));
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  }
  std::vector<int> label(vertex_count, -1);
  count = 0;
  for (int v = 0; v < vertex_count; ++v) {
    const int root = find(v);
    if (label[root] < 0) label[root] = count++;
    label[v] = label[root];
  }
  return label;
}

// Pairs of enabled triangles that share an edge (all pairs where an edge is non-manifold).
std::vector<std::array<int, 2>> adjacent_triangles(const Triangles& F, const std::vector<char>& enabled) {
  struct Edge {
    int a, b, triangle;
  };
  std::vector<Edge> edges;
  edges.reserve(3 * F.rows());
  for (int t = 0; t < F.rows(); ++t) {
    if (!enabled[t]) continue;
    for (int k = 0; k < 3; ++k) {
      const int i = F(t, k), j = F(t, (k + 1) % 3);
      edges.push_back({std::min(i, j), std::max(i, j), t});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) {
    return std::tie(x.a, x.b, x.triangle) < std::tie(y.a, y.b, y.triangle);
  });
  std::vector<std::array<int, 2>> pairs;
  for (size_t begin = 0, end; begin < edges.size(); begin = end) {
    for (end = begin + 1; end < edges.size() && edges[end].a == edges[begin].a && edges[end].b == edges[begin].b;
         ++end) {
    }
    for (size_t p = begin; p < end; ++p)
      for (size_t q = p + 1; q < end; ++q)
        if (edges[p].triangle != edges[q].triangle) pairs.push_back({edges[p].triangle, edges[q].triangle});
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

// Adds weight * G^T G over the unknowns `index` (4 of them) as triplets.
void add_gram(const Operator& G, const std::array<int, 4>& index, double weight, std::vector<Triplet>& out) {
  const Eigen::Matrix4d gram = weight * G.transpose() * G;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out.emplace_back(index[r], index[c], gram(r, c));
}

std::array<int, 4> unknowns(const Triangles& F, int vertex_count, int t) {
  return {F(t, 0), F(t, 1), F(t, 2), vertex_count + t};
}

void check_mesh(const Mesh& mesh, const char* role) {
  if (mesh.vertex_count() == 0 || mesh.triangle_count() == 0)
    throw Error("deformation transfer", fmt::format("the {} has no {}", describe(mesh, role),
                                                    mesh.vertex_count() == 0 ? "vertices" : "triangles"));
  if (mesh.triangles.minCoeff() < 0 || mesh.triangles.maxCoeff() >= mesh.vertex_count())
    throw Error("deformation transfer", fmt::format("the {} has a triangle with a vertex index outside [0, {})",
                                                    describe(mesh, role), mesh.vertex_count()));
  if (!mesh.vertices.allFinite())
    throw Error("deformation transfer", fmt::format("the {} has a non-finite vertex coordinate", describe(mesh, role)));
}

void check_landmarks(const std::vector<LandmarkPair>& landmarks, const Mesh& source, const Mesh& target) {
  if (landmarks.size() < 3)
    throw Error("deformation transfer landmarks",
                fmt::format("need at least 3 landmark pairs, got {}", landmarks.size()));
  std::vector<int> used_by(source.vertex_count(), -1);
  for (size_t k = 0; k < landmarks.size(); ++k) {
    const LandmarkPair& l = landmarks[k];
    if (l.source < 0 || l.source >= source.vertex_count())
      throw Error(fmt::format("landmark {}", k),
                  fmt::format("source vertex index {} is out of range: the {} has {} vertices", l.source,
                              describe(source, "source rest mesh"), source.vertex_count()));
    if (l.target < 0 || l.target >= target.vertex_count())
      throw Error(fmt::format("landmark {}", k),
                  fmt::format("target vertex index {} is out of range: the {} has {} vertices", l.target,
                              describe(target, "target rest mesh"), target.vertex_count()));
    if (used_by[l.source] >= 0)
      throw Error(fmt::format("landmark {}", k),
                  fmt::format("source vertex {} is already landmark {}; each source vertex can "
                              "land on one target vertex only",
                              l.source, used_by[l.source]));
    used_by[l.source] = static_cast<int>(k);
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------

void DeformationTransferOptions::validate() const {
  auto fail = [](const std::string& name, const std::string& what) {
    throw Error("deformation_transfer." + name, what);
  };
  auto non_negative = [&](const std::string& name, double value) {
    if (!(std::isfinite(value) && value >= 0)) fail(name, fmt::format("expected a finite number >= 0, got {}", value));
  };
  non_negative("smoothness_weight", smoothness_weight);
  if (!(std::isfinite(identity_weight) && identity_weight > 0))
    fail("identity_weight",
         fmt::format("expected a finite number > 0 (it keeps the fit well-posed), got {}", identity_weight));
  if (closest_point_weights.empty())
    fail("closest_point_weights", "expected at least one weight (one solve per weight)");
  for (size_t k = 0; k < closest_point_weights.size(); ++k)
    non_negative(fmt::format("closest_point_weights[{}]", k), closest_point_weights[k]);
  non_negative("landmark_weight", landmark_weight);
  if (!(max_normal_angle_deg > 0 && max_normal_angle_deg <= 180))
    fail("max_normal_angle_deg", fmt::format("expected an angle in (0, 180] degrees, got {}", max_normal_angle_deg));
  non_negative("match_distance", match_distance);
  if (prealignment != Prealignment::none && prealignment != Prealignment::translation_scale &&
      prealignment != Prealignment::similarity)
    fail("prealignment", "expected none, translation_scale or similarity");
  if (translation_anchor != TranslationAnchor::follow_source && translation_anchor != TranslationAnchor::keep_centroid)
    fail("translation_anchor", "expected follow_source or keep_centroid");
}

// ---------------------------------------------------------------------------------------

struct DeformationTransfer::Impl {
  DeformationTransferOptions options;
  Report report;

  // Source side.
  int source_vertices = 0;
  Triangles source_triangles;
  Positions source_rest;         // as given, source units
  Similarity similarity;         // source -> target frame
  bool rotated = false;          // similarity.rotation != I
  TriangleFrames source_frames;  // of source_rest (raw frame)
  // Per source triangle: frame(rest)^-1 R^T, so that R (frame(deformed) * this) is the
  // deformation gradient expressed in the target's frame.
  std::vector<Eigen::Matrix3d> source_gradient_map;
  Positions fitted;  // #Vs x 3, target frame

  // Pairing.
  std::vector<std::pair<int, int>> pairs;  // (source, target), sorted
  // Per target triangle: its paired source triangles pair_source[pair_start[t] ..
  // pair_start[t + 1]), and whether it is held to the identity instead.
  std::vector<int> pair_start, pair_source;
  std::vector<char> identity_triangle;

  // Target side.
  int target_vertices = 0;
  Triangles target_triangles;
  Positions target_rest;
  TriangleFrames target_frames;
  std::vector<Operator> target_operator;  // #Tt, zero for invalid triangles
  std::optional<PinnedCholesky> solver;
  Rhs3 pinned_values;
  // Translation: target vertex components, each with its vertices and the source vertex
  // weights of its vertices' corresponding points (averaged), sum 1.
  std::vector<int> target_component;
  int component_count = 0;
  std::vector<int> component_size;
  std::vector<std::vector<std::pair<int, double>>> component_source_weights;

  void correspond(const Mesh& source, const Mesh& target, const std::vector<LandmarkPair>& landmarks);
  void pair_triangles();
  void factorise();
  void check(const Positions& source_deformed, const std::string& where) const;
  Positions run(const Positions& source_deformed) const;
};

void DeformationTransfer::Impl::correspond(const Mesh& source, const Mesh& target,
                                           const std::vector<LandmarkPair>& landmarks) {
  const auto start = Clock::now();
  const int nv = source_vertices;
  const int nt = static_cast<int>(source_triangles.rows());
  const int n = nv + nt;
  const Triangles& F = source_triangles;

  Eigen::Matrix3Xd from(3, landmarks.size()), to(3, landmarks.size());
  for (size_t k = 0; k < landmarks.size(); ++k) {
    from.col(k) = source.vertices.row(landmarks[k].source).transpose();
    to.col(k) = target.vertices.row(landmarks[k].target).transpose();
  }
  similarity = prealign(from, to, options.prealignment);
  rotated = !similarity.rotation.isIdentity(0);
  report.prealignment_scale = similarity.scale;
  const Positions aligned = similarity.apply(source.vertices);

  source_frames = triangle_frames(source.vertices, F);
  report.degenerate_source_triangles = source_frames.invalid_count();
  const std::vector<char>& valid = source_frames.valid;
  source_gradient_map.resize(nt);
  std::vector<Operator> G(nt, Operator::Zero());
  for (int t = 0; t < nt; ++t) {
    source_gradient_map[t] = source_frames.inverse[t] * similarity.rotation.transpose();
    // The aligned frame is scale * R * frame, so its inverse is frame^-1 R^T / scale.
    if (valid[t]) G[t] = gradient_operator(source_gradient_map[t] / similarity.scale);
  }

  const double h = mean_edge_length(aligned, F);
  if (!(h > 0))
    throw Error("deformation transfer",
                fmt::format("the {} has only zero-length edges", describe(source, "source rest mesh")));
  const double unit = 1.0 / (h * h);  // distances in edge lengths

  // Constant part: w_S E_S + w_I E_I, and the diagonal of every unknown (so that the
  // per-solve diagonal terms never change the pattern refactor() relies on).
  std::vector<Triplet> triplets;
  Rhs3 rhs_constant = Rhs3::Zero(n, 3);
  const auto adjacent = adjacent_triangles(F, valid);
  triplets.reserve(16 * nt + 64 * adjacent.size() + n);
  for (int i = 0; i < n; ++i) triplets.emplace_back(i, i, 0.0);
  for (int t = 0; t < nt; ++t) {
    const auto index = unknowns(F, nv, t);
    if (!valid[t]) {
      triplets.emplace_back(index[3], index[3], 1.0);  // a free fourth vertex, kept at 0
      continue;
    }
    add_gram(G[t], index, options.identity_weight, triplets);
    for (int k = 0; k < 4; ++k) rhs_constant.row(index[k]) += options.identity_weight * G[t].col(k).transpose();
  }
  if (options.smoothness_weight > 0) {
    for (const auto& [a, b] : adjacent) {
      Eigen::Matrix<double, 3, 8> D;
      D << G[a], -G[b];
      const auto ia = unknowns(F, nv, a), ib = unknowns(F, nv, b);
      const std::array<int, 8> index{ia[0], ia[1], ia[2], ia[3], ib[0], ib[1], ib[2], ib[3]};
      const Eigen::Matrix<double, 8, 8> gram = options.smoothness_weight * D.transpose() * D;
      for (int r = 0; r < 8; ++r)
        for (int c = 0; c < 8; ++c) triplets.emplace_back(index[r], index[c], gram(r, c));
    }
  }
  SparseMatrix constant(n, n);
  constant.setFromTriplets(triplets.begin(), triplets.end());
  triplets = {};

  // Landmarks: pinned (hard) or pulled (soft); parts of the source without a landmark get
  // a faint pull to where they are, so that the first solves are well-posed.
  const bool hard = options.landmark_weight == 0;
  std::vector<char> is_landmark(nv, 0);
  for (const auto& l : landmarks) is_landmark[l.source] = 1;
  int part_count = 0;
  const std::vector<int> part = components(nv, F, valid, part_count);
  std::vector<char> part_has_landmark(part_count, 0);
  for (const auto& l : landmarks) part_has_landmark[part[l.source]] = 1;
  std::vector<int> pinned;
  Rhs3 pinned_positions;
  if (hard) {
    pinned_positions.resize(landmarks.size(), 3);
    for (size_t k = 0; k < landmarks.size(); ++k) {
      pinned.push_back(landmarks[k].source);
      pinned_positions.row(k) = target.vertices.row(landmarks[k].target);
    }
  }

  const ClosestSurfacePoint target_surface(target.vertices, target.triangles);
  const double min_cosine = std::cos(options.max_normal_angle_deg * M_PI / 180.0);
  Rhs3 x = Rhs3::Zero(n, 3);
  x.topRows(nv) = aligned;
  if (hard)
    for (size_t k = 0; k < landmarks.size(); ++k) x.row(landmarks[k].source) = pinned_positions.row(k);

  auto distances = [&](Report::Step& step) {
    std::vector<double> d(nv);
#pragma omp parallel for schedule(static)
    for (int i = 0; i < nv; ++i) d[i] = std::sqrt(target_surface.closest(x.row(i).transpose()).squared_distance);
    step.mean_distance = std::accumulate(d.begin(), d.end(), 0.0) / nv;
    step.max_distance = *std::max_element(d.begin(), d.end());
  };

  std::optional<PinnedCholesky> cholesky;
  std::vector<SurfacePoint> closest(nv);
  for (double weight : options.closest_point_weights) {
    Report::Step step;
    step.closest_point_weight = weight;
    SparseMatrix A = constant;
    Rhs3 b = rhs_constant;
    if (weight > 0) {
      const Positions current = x.topRows(nv);
      const Positions normals = vertex_normals(current, F, valid);
#pragma omp parallel for schedule(dynamic, 256)
      for (int i = 0; i < nv; ++i) {
        closest[i] = SurfacePoint{};
        const Eigen::Vector3d normal = normals.row(i);
        if (is_landmark[i] || normal.squaredNorm() == 0) continue;
        closest[i] = target_surface.closest(current.row(i).transpose(), normal, min_cosine);
      }
      for (int i = 0; i < nv; ++i) {
        if (!closest[i].found()) continue;
        ++step.closest_points;
        A.coeffRef(i, i) += weight * unit;
        b.row(i) += weight * unit * closest[i].point.transpose();
      }
    }
    for (int i = 0; i < nv; ++i) {
      if (!part_has_landmark[part[i]]) {
        A.coeffRef(i, i) += kAnchorWeight * unit;
        b.row(i) += kAnchorWeight * unit * x.row(i);
      }
    }
    if (!hard) {
      const double w = options.landmark_weight * unit;
      for (const auto& l : landmarks) {
        A.coeffRef(l.source, l.source) += w;
        b.row(l.source) += w * target.vertices.row(l.target);
      }
    }
    if (cholesky)
      cholesky->refactor(A);
    else
      cholesky.emplace(A, pinned);
    cholesky->solve(b, pinned_positions, x);
    distances(step);
    report.steps.push_back(step);
  }
  fitted = x.topRows(nv);
  report.mean_distance = report.steps.back().mean_distance;
  report.max_distance = report.steps.back().max_distance;
  report.correspondence_seconds = seconds_since(start);
}

void DeformationTransfer::Impl::pair_triangles() {
  const auto start = Clock::now();
  const Triangles& S = source_triangles;
  const Triangles& T = target_triangles;
  const int ns = static_cast<int>(S.rows()), nt = static_cast<int>(T.rows());
  const Positions source_centroids = triangle_centroids(fitted, S);
  const Positions source_normals = triangle_normals(fitted, S);
  const Positions target_centroids = triangle_centroids(target_rest, T);
  const Positions target_normals = triangle_normals(target_rest, T);
  std::vector<char> source_ok(ns), target_ok(nt);
  for (int s = 0; s < ns; ++s) source_ok[s] = source_frames.valid[s] && source_normals.row(s).squaredNorm() > 0;
  for (int t = 0; t < nt; ++t) target_ok[t] = target_frames.valid[t];

  const double radius = options.match_distance > 0
                            ? options.match_distance
                            : 3 * std::max(mean_edge_length(fitted, S), mean_edge_length(target_rest, T));
  report.match_distance = radius;
  const double min_cosine = std::cos(options.max_normal_angle_deg * M_PI / 180.0);
  const NearestPoints source_search(source_centroids, source_ok);
  const NearestPoints target_search(target_centroids, target_ok);

  std::vector<int> source_for(nt, -1), target_for(ns, -1);
#pragma omp parallel for schedule(dynamic, 256)
  for (int t = 0; t < nt; ++t) {
    if (!target_ok[t]) continue;
    const Eigen::RowVector3d normal = target_normals.row(t);
    source_for[t] = source_search.nearest(
        target_centroids.row(t).transpose(), [&](int s) { return source_normals.row(s).dot(normal) >= min_cosine; },
        radius);
  }
#pragma omp parallel for schedule(dynamic, 256)
  for (int s = 0; s < ns; ++s) {
    if (!source_ok[s]) continue;
    const Eigen::RowVector3d normal = source_normals.row(s);
    target_for[s] = target_search.nearest(
        source_centroids.row(s).transpose(), [&](int t) { return target_normals.row(t).dot(normal) >= min_cosine; },
        radius);
  }
  pairs.clear();
  for (int t = 0; t < nt; ++t)
    if (source_for[t] >= 0) pairs.emplace_back(source_for[t], t);
  for (int s = 0; s < ns; ++s)
    if (target_for[s] >= 0) pairs.emplace_back(s, target_for[s]);

  // Every target triangle must be in some pair, or its fourth vertex and possibly its
  // corners would be free in the transfer system.
  std::vector<char> paired(nt, 0);
  for (const auto& p : pairs) paired[p.second] = 1;
  std::vector<int> fallback(nt, -1);
#pragma omp parallel for schedule(dynamic, 64)
  for (int t = 0; t < nt; ++t) {
    if (!target_ok[t] || paired[t]) continue;
    const Eigen::RowVector3d normal = target_normals.row(t);
    fallback[t] = source_search.nearest(
        target_centroids.row(t).transpose(), [&](int s) { return source_normals.row(s).dot(normal) >= min_cosine; },
        std::numeric_limits<double>::infinity(), kFallbackVisits);
  }
  identity_triangle.assign(nt, 0);
  for (int t = 0; t < nt; ++t) {
    if (!target_ok[t] || paired[t]) continue;
    if (fallback[t] >= 0) {
      pairs.emplace_back(fallback[t], t);
      ++report.fallback_target_triangles;
    } else {
      identity_triangle[t] = 1;
      ++report.identity_target_triangles;
    }
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  report.triangle_pairs = static_cast<int>(pairs.size());

  pair_start.assign(nt + 1, 0);
  for (const auto& p : pairs) ++pair_start[p.second + 1];
  std::partial_sum(pair_start.begin(), pair_start.end(), pair_start.begin());
  pair_source.resize(pairs.size());
  std::vector<int> fill(pair_start.begin(), pair_start.end() - 1);
  for (const auto& p : pairs) pair_source[fill[p.second]++] = p.first;
  report.pairing_seconds = seconds_since(start);
}

void DeformationTransfer::Impl::factorise() {
  const auto start = Clock::now();
  const Triangles& T = target_triangles;
  const int nv = target_vertices, nt = static_cast<int>(T.rows()), n = nv + nt;
  target_operator.assign(nt, Operator::Zero());
  std::vector<Triplet> triplets;
  triplets.reserve(16 * nt + nv);
  // Vertices in no valid triangle still need a diagonal; they are pinned below.
  for (int i = 0; i < nv; ++i) triplets.emplace_back(i, i, 0.0);
  for (int t = 0; t < nt; ++t) {
    const auto index = unknowns(T, nv, t);
    const int terms = pair_start[t + 1] - pair_start[t] + identity_triangle[t];
    if (!target_frames.valid[t] || terms == 0) {
      triplets.emplace_back(index[3], index[3], 1.0);
      continue;
    }
    target_operator[t] = gradient_operator(target_frames.inverse[t]);
    add_gram(target_operator[t], index, terms, triplets);
  }
  SparseMatrix A(n, n);
  A.setFromTriplets(triplets.begin(), triplets.end());
  triplets = {};

  // Gradients fix everything but one translation per connected part: pin one vertex of
  // each (at rest) and restore the translation after the solve.
  target_component = components(nv, T, target_frames.valid, component_count);
  report.target_components = component_count;
  std::vector<int> pinned(component_count, -1);
  component_size.assign(component_count, 0);
  for (int i = 0; i < nv; ++i) {
    if (pinned[target_component[i]] < 0) pinned[target_component[i]] = i;
    ++component_size[target_component[i]];
  }
  pinned_values.resize(component_count, 3);
  for (int c = 0; c < component_count; ++c) pinned_values.row(c) = target_rest.row(pinned[c]);
  solver.emplace(A, pinned);

  // Corresponding source points of the target vertices, on the fitted source surface.
  component_source_weights.assign(component_count, {});
  if (options.translation_anchor == DeformationTransferOptions::TranslationAnchor::follow_source) {
    const ClosestSurfacePoint fitted_surface(fitted, source_triangles, source_frames.valid);
    const Positions normals = vertex_normals(target_rest, T, target_frames.valid);
    const double min_cosine = std::cos(options.max_normal_angle_deg * M_PI / 180.0);
    std::vector<SurfacePoint> corresponding(nv);
#pragma omp parallel for schedule(dynamic, 256)
    for (int i = 0; i < nv; ++i) {
      const Eigen::Vector3d p = target_rest.row(i), normal = normals.row(i);
      SurfacePoint hit;
      if (normal.squaredNorm() > 0) hit = fitted_surface.closest(p, normal, min_cosine);
      if (!hit.found()) hit = fitted_surface.closest(p);
      corresponding[i] = hit;
    }
    struct Weight {
      int component, vertex;
      double weight;
    };
    std::vector<Weight> weights;
    weights.reserve(3 * nv);
    for (int i = 0; i < nv; ++i) {
      const SurfacePoint& hit = corresponding[i];
      if (!hit.found()) continue;
      const int c = target_component[i];
      for (int k = 0; k < 3; ++k)
        weights.push_back({c, source_triangles(hit.triangle, k), hit.barycentric[k] / component_size[c]});
    }
    std::sort(weights.begin(), weights.end(), [](const Weight& a, const Weight& b) {
      return std::tie(a.component, a.vertex) < std::tie(b.component, b.vertex);
    });
    for (const Weight& w : weights) {
      auto& list = component_source_weights[w.component];
      if (!list.empty() && list.back().first == w.vertex)
        list.back().second += w.weight;
      else
        list.emplace_back(w.vertex, w.weight);
    }
  }
  report.factorisation_seconds = seconds_since(start);
}

void DeformationTransfer::Impl::check(const Positions& source_deformed, const std::string& where) const {
  if (source_deformed.rows() != source_vertices)
    throw Error(where, fmt::format("source_deformed has {} vertices but the source rest mesh has "
                                   "{}; expressions must share the source rest topology",
                                   source_deformed.rows(), source_vertices));
  if (!source_deformed.allFinite()) throw Error(where, "source_deformed has a non-finite (NaN or infinite) coordinate");
}

Positions DeformationTransfer::Impl::run(const Positions& source_deformed) const {
  const Triangles& S = source_triangles;
  const Triangles& T = target_triangles;
  const int nv = target_vertices, nt = static_cast<int>(T.rows());
  Rhs3 b = Rhs3::Zero(nv + nt, 3);
  for (int t = 0; t < nt; ++t) {
    const int first = pair_start[t], last = pair_start[t + 1];
    if (last == first && !identity_triangle[t]) continue;
    // The transfer matches the target gradient to each paired source gradient; the normal
    // equations only need their sum.
    Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
    for (int p = first; p < last; ++p) {
      const int s = pair_source[p];
      sum.noalias() +=
          triangle_frame(source_deformed.row(S(s, 0)), source_deformed.row(S(s, 1)), source_deformed.row(S(s, 2))) *
          source_gradient_map[s];
    }
    if (rotated) sum = (similarity.rotation * sum).eval();
    if (identity_triangle[t]) sum += Eigen::Matrix3d::Identity();
    const Operator& G = target_operator[t];
    const auto index = unknowns(T, nv, t);
    for (int k = 0; k < 4; ++k) b.row(index[k]) += (sum * G.col(k)).transpose();
  }
  Rhs3 x;
  solver->solve(b, pinned_values, x);
  Positions out = x.topRows(nv);

  // Restore each part's translation.
  std::vector<Eigen::RowVector3d> shift(component_count, Eigen::RowVector3d::Zero());
  for (int i = 0; i < nv; ++i) shift[target_component[i]] -= out.row(i) - target_rest.row(i);
  for (int c = 0; c < component_count; ++c) {
    shift[c] /= component_size[c];
    if (component_source_weights[c].empty()) continue;
    Eigen::Vector3d moved = Eigen::Vector3d::Zero();
    for (const auto& [v, w] : component_source_weights[c])
      moved += w * (source_deformed.row(v) - source_rest.row(v)).transpose();
    shift[c] += (similarity.scale * similarity.rotation * moved).transpose();
  }
  for (int i = 0; i < nv; ++i) out.row(i) += shift[target_component[i]];
  return out;
}

// ---------------------------------------------------------------------------------------

DeformationTransfer::DeformationTransfer(const Mesh& source_rest, const Mesh& target_rest,
                                         std::vector<LandmarkPair> landmarks, DeformationTransferOptions options)
    : impl_(std::make_unique<Impl>()) {
  options.validate();
  check_mesh(source_rest, "source rest mesh");
  check_mesh(target_rest, "target rest mesh");
  check_landmarks(landmarks, source_rest, target_rest);
  Impl& m = *impl_;
  m.options = std::move(options);
  m.source_vertices = source_rest.vertex_count();
  m.source_triangles = source_rest.triangles;
  m.source_rest = source_rest.vertices;
  m.target_vertices = target_rest.vertex_count();
  m.target_triangles = target_rest.triangles;
  m.target_rest = target_rest.vertices;
  m.target_frames = triangle_frames(target_rest.vertices, target_rest.triangles);
  m.report.degenerate_target_triangles = m.target_frames.invalid_count();
  m.correspond(source_rest, target_rest, landmarks);
  m.pair_triangles();
  m.factorise();
}

DeformationTransfer::~DeformationTransfer() = default;
DeformationTransfer::DeformationTransfer(DeformationTransfer&&) noexcept = default;
DeformationTransfer& DeformationTransfer::operator=(DeformationTransfer&&) noexcept = default;

Positions DeformationTransfer::transfer(const Positions& source_deformed) const {
  impl_->check(source_deformed, "deformation transfer");
  return impl_->run(source_deformed);
}

std::vector<Positions> DeformationTransfer::transfer(const std::vector<Positions>& source_deformed) const {
  // Checked up front: exceptions must not leave the parallel loop.
  for (size_t k = 0; k < source_deformed.size(); ++k)
    impl_->check(source_deformed[k], fmt::format("deformation transfer, expression {}", k));
  std::vector<Positions> out(source_deformed.size());
  const int count = static_cast<int>(source_deformed.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < count; ++k) out[k] = impl_->run(source_deformed[k]);
  return out;
}

const Positions& DeformationTransfer::fitted_source() const { return impl_->fitted; }
const std::vector<std::pair<int, int>>& DeformationTransfer::triangle_pairs() const { return impl_->pairs; }
const DeformationTransfer::Report& DeformationTransfer::report() const { return impl_->report; }

Positions deformation_transfer(const Mesh& source_rest, const Positions& source_deformed, const Mesh& target_rest,
                               const std::vector<LandmarkPair>& landmarks, const DeformationTransferOptions& options) {
  // Check the expression before the (expensive) correspondence phase.
  if (source_deformed.rows() != source_rest.vertex_count())
    throw Error("deformation transfer", fmt::format("source_deformed has {} vertices but the source rest mesh has {}; "
                                                    "expressions must share the source rest topology",
                                                    source_deformed.rows(), source_rest.vertex_count()));
  return DeformationTransfer(source_rest, target_rest, landmarks, options).transfer(source_deformed);
}

}  // namespace retarget
