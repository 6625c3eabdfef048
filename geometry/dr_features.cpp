#include "geometry/dr_features.h"

#include <omp.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "geometry/dr_pack_lanes.h"
#include "geometry/rotation.h"

namespace retarget {

void DrOptions::validate() const {
  if (threads < 0)
    throw Error("dr.threads", "expected 0 (all cores) or a positive count, got " + std::to_string(threads));
  if (!(normal_weight > 0) || !std::isfinite(normal_weight))
    throw Error("dr.normal_weight", "expected a positive number, got " + std::to_string(normal_weight));
}

void pack_dr(const Eigen::Matrix3d& R, const Eigen::Matrix3d& S, float* out) {
  const Eigen::Vector3d r = rotation_log(R);
  out[0] = static_cast<float>(r.x());
  out[1] = static_cast<float>(r.y());
  out[2] = static_cast<float>(r.z());
  out[3] = static_cast<float>(S(0, 0) - 1);
  out[4] = static_cast<float>(S(0, 1));
  out[5] = static_cast<float>(S(0, 2));
  out[6] = static_cast<float>(S(1, 1) - 1);
  out[7] = static_cast<float>(S(1, 2));
  out[8] = static_cast<float>(S(2, 2) - 1);
}

Eigen::Matrix3d unpack_dr(const float* in) {
  Eigen::Matrix3d S;
  S << in[3] + 1.0, in[4], in[5],  //
      in[4], in[6] + 1.0, in[7],   //
      in[5], in[7], in[8] + 1.0;
  return rotation_exp(Eigen::Vector3d(in[0], in[1], in[2])) * S;
}

namespace {
// Pseudo-inverse of a symmetric positive semi-definite 3 x 3 matrix: directions with
// (almost) no rest edge along them map to zero instead of to infinity.
Eigen::Matrix3d symmetric_pseudo_inverse(const Eigen::Matrix3d& M) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(M);
  const Eigen::Vector3d& lambda = eig.eigenvalues();
  const double cutoff = 1e-10 * std::max(lambda.cwiseAbs().maxCoeff(), 1e-300);
  Eigen::Vector3d inv;
  for (int k = 0; k < 3; ++k) inv[k] = lambda[k] > cutoff ? 1.0 / lambda[k] : 0.0;
  return eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
}
}  // namespace

DrFeatures::DrFeatures(const Mesh& rest, DrOptions options)
    : options_(options), vertex_count_(rest.vertex_count()), triangles_(rest.triangles) {
  options_.validate();
  const EdgeTopology topology = edge_topology(rest.triangles);
  const Eigen::VectorXd edge_w = edge_weights(rest.vertices, topology, options_.weighting);
  neighbors_ = vertex_neighbors(topology, vertex_count_);
  incident_ = vertex_triangles(rest.triangles, vertex_count_);

  // Weight of each neighbour entry: look the edge up through the same fill order
  // vertex_neighbors() used (edges in order, each pushed to both ends).
  weight_.assign(neighbors_.items.size(), 0.0);
  {
    std::vector<int> fill(neighbors_.start.begin(), neighbors_.start.end() - 1);
    for (size_t e = 0; e < topology.edges.size(); ++e) {
      weight_[fill[topology.edges[e][0]]++] = edge_w[e];
      weight_[fill[topology.edges[e][1]]++] = edge_w[e];
    }
  }
  const Positions& V = rest.vertices;
  weighted_rest_edge_.resize(neighbors_.items.size());
  weight_sum_.assign(vertex_count_, 0.0);
  weighted_rest_normal_.assign(vertex_count_, Eigen::Vector3d::Zero());
  rest_inverse_.resize(vertex_count_);
  std::vector<Eigen::Vector3d> rest_normals(triangles_.rows());
  triangle_normals(V, 0, static_cast<int>(triangles_.rows()), rest_normals.data());
  // Each vertex on its own (its one-ring's entries, its sums, its inverse): in parallel.
#pragma omp parallel for num_threads(threads()) schedule(static, 512)
  for (int i = 0; i < vertex_count_; ++i) {
    Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
    double length2 = 0;
    for (int k = neighbors_.start[i]; k < neighbors_.start[i + 1]; ++k) {
      const Eigen::Vector3d e = (V.row(neighbors_.items[k]) - V.row(i)).transpose();
      weighted_rest_edge_[k] = weight_[k] * e;
      M += weighted_rest_edge_[k] * e.transpose();
      weight_sum_[i] += weight_[k];
      length2 += weight_[k] * e.squaredNorm();
    }
    const int degree = neighbors_.size(i);
    if (options_.normal_term && degree > 0 && weight_sum_[i] > 0) {
      const Eigen::Vector3d n = vertex_normal(rest_normals.data(), i);
      const double norm = n.norm();
      if (norm > 0) {
        const Eigen::Vector3d scaled = n * (std::sqrt(length2 / weight_sum_[i]) / norm);
        weighted_rest_normal_[i] = (options_.normal_weight * weight_sum_[i] / degree) * scaled;
        M += weighted_rest_normal_[i] * scaled.transpose();
      }
    }
    rest_inverse_[i] = symmetric_pseudo_inverse(M);
  }
}

void DrFeatures::triangle_normals(const Positions& P, int begin, int end, Eigen::Vector3d* out) const {
  for (int t = begin; t < end; ++t) {
    const Eigen::Vector3d a = P.row(triangles_(t, 0)).transpose();
    out[t] = (P.row(triangles_(t, 1)).transpose() - a).cross(P.row(triangles_(t, 2)).transpose() - a);
  }
}

Eigen::Vector3d DrFeatures::vertex_normal(const Eigen::Vector3d* normals, int vertex) const {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (int k = incident_.start[vertex]; k < incident_.start[vertex + 1]; ++k) n += normals[incident_.items[k]];
  return n;
}

Eigen::Matrix3d DrFeatures::gradient(const Positions& P, const Eigen::Vector3d* normals, int i) const {
  const Eigen::Vector3d p = P.row(i).transpose();
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  double length2 = 0;
  for (int k = neighbors_.start[i]; k < neighbors_.start[i + 1]; ++k) {
    const Eigen::Vector3d d = P.row(neighbors_.items[k]).transpose() - p;
    A.noalias() += d * weighted_rest_edge_[k].transpose();
    length2 += weight_[k] * d.squaredNorm();
  }
  if (options_.normal_term && weight_sum_[i] > 0) {
    const Eigen::Vector3d n = vertex_normal(normals, i);
    const double norm = n.norm();
    if (norm > 0)
      A.noalias() += (n * (std::sqrt(length2 / weight_sum_[i]) / norm)) * weighted_rest_normal_[i].transpose();
  }
  return A * rest_inverse_[i];
}

Eigen::Matrix3d DrFeatures::deformation_gradient(const Positions& deformed, int vertex) const {
  std::vector<Eigen::Vector3d> normals(triangles_.rows());
  triangle_normals(deformed, 0, static_cast<int>(triangles_.rows()), normals.data());
  return gradient(deformed, normals.data(), vertex);
}

void DrFeatures::compute_range(const Positions& P, const Eigen::Vector3d* normals, int begin, int end,
                               float* out) const {
  // Gradients a chunk at a time (on the stack), then their polar decompositions and logs in vector
  // lanes (geometry/dr_pack_lanes.h).
  constexpr int kChunk = 64;
  Eigen::Matrix3d chunk[kChunk];
  for (int first = begin; first < end; first += kChunk) {
    const int count = std::min(kChunk, end - first);
    for (int k = 0; k < count; ++k) chunk[k] = gradient(P, normals, first + k);
    pack_dr_lanes(chunk, count, out + static_cast<size_t>(first) * kDrWidth);
  }
}

int DrFeatures::threads() const { return options_.threads > 0 ? options_.threads : omp_get_max_threads(); }

void DrFeatures::compute(const Positions& deformed, float* out) const {
  if (deformed.rows() != vertex_count_)
    throw Error("DR features", "the deformed mesh has " + std::to_string(deformed.rows()) +
                                   " vertices but the rest mesh has " + std::to_string(vertex_count_));
  constexpr int kBlock = 512;
  const int triangle_count = static_cast<int>(triangles_.rows());
  std::vector<Eigen::Vector3d> normals(options_.normal_term ? triangle_count : 0);
  const int vertex_blocks = (vertex_count_ + kBlock - 1) / kBlock;
  const int triangle_blocks = options_.normal_term ? (triangle_count + kBlock - 1) / kBlock : 0;
#pragma omp parallel num_threads(threads())
  {
#pragma omp for schedule(static)
    for (int b = 0; b < triangle_blocks; ++b)
      triangle_normals(deformed, b * kBlock, std::min(triangle_count, (b + 1) * kBlock), normals.data());
#pragma omp for schedule(static)
    for (int b = 0; b < vertex_blocks; ++b)
      compute_range(deformed, normals.data(), b * kBlock, std::min(vertex_count_, (b + 1) * kBlock), out);
  }
}

DrFeatureMatrix DrFeatures::compute(const Positions& deformed) const {
  DrFeatureMatrix features(vertex_count_, kDrWidth);
  compute(deformed, features.data());
  return features;
}

void DrFeatures::compute_batch(const std::vector<const Positions*>& deformed, float* out) const {
  const int count = static_cast<int>(deformed.size());
  for (int b = 0; b < count; ++b)
    if (deformed[b]->rows() != vertex_count_)
      throw Error("DR features", "mesh " + std::to_string(b) + " of the batch has " +
                                     std::to_string(deformed[b]->rows()) + " vertices but the rest mesh has " +
                                     std::to_string(vertex_count_));
  const size_t stride = static_cast<size_t>(vertex_count_) * kDrWidth;
  if (count < 2 * threads()) {
    for (int b = 0; b < count; ++b) compute(*deformed[b], out + b * stride);
    return;
  }
  const int triangle_count = static_cast<int>(triangles_.rows());
#pragma omp parallel num_threads(threads())
  {
    std::vector<Eigen::Vector3d> normals(options_.normal_term ? triangle_count : 0);
#pragma omp for schedule(dynamic, 1)
    for (int b = 0; b < count; ++b) {
      if (options_.normal_term) triangle_normals(*deformed[b], 0, triangle_count, normals.data());
      compute_range(*deformed[b], normals.data(), 0, vertex_count_, out + b * stride);
    }
  }
}

}  // namespace retarget
