#include "geometry/reconstruction.h"

#include <omp.h>

#include "core/error.h"
#include "geometry/dr_features.h"
#include "geometry/mesh_topology.h"
#include "geometry/part_motion.h"
#include "geometry/rigid_alignment.h"

namespace retarget {

void ReconstructionOptions::validate() const {
  for (int v : anchors)
    if (v < 0) throw Error("reconstruction.anchors", "vertex index " + std::to_string(v) + " is negative");
  if (threads < 0)
    throw Error("reconstruction.threads", "expected 0 (all cores) or a positive count, got " + std::to_string(threads));
}

struct Reconstruction::Prepared {
  EdgeTopology topology;
  Eigen::VectorXd weight;
  Components components;
  SparseMatrix laplacian;
};

Reconstruction::Prepared Reconstruction::prepare(const Mesh& rest, EdgeWeighting weighting) {
  Prepared p;
  p.topology = edge_topology(rest.triangles);
  p.weight = edge_weights(rest.vertices, p.topology, weighting);
  p.components = connected_components(p.topology, rest.vertex_count());
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(4 * p.topology.edges.size());
  for (size_t e = 0; e < p.topology.edges.size(); ++e) {
    const int i = p.topology.edges[e][0], j = p.topology.edges[e][1];
    const double w = p.weight[e];
    entries.emplace_back(i, i, w);
    entries.emplace_back(j, j, w);
    entries.emplace_back(i, j, -w);
    entries.emplace_back(j, i, -w);
  }
  p.laplacian.resize(rest.vertex_count(), rest.vertex_count());
  p.laplacian.setFromTriplets(entries.begin(), entries.end());
  return p;
}

Reconstruction::Reconstruction(const Mesh& rest, ReconstructionOptions options)
    : Reconstruction(rest, options, prepare(rest, options.weighting)) {}

std::vector<int> Reconstruction::pins(const ReconstructionOptions& options, const std::vector<int>& component,
                                      const std::vector<int>& first_vertex) {
  options.validate();
  const int vertex_count = static_cast<int>(component.size());
  std::vector<char> anchored(first_vertex.size(), 0), seen(static_cast<size_t>(vertex_count), 0);
  std::vector<int> out;
  for (int v : options.anchors) {
    if (v >= vertex_count)
      throw Error("reconstruction.anchors", "vertex " + std::to_string(v) + " is out of range (the mesh has " +
                                                std::to_string(vertex_count) + " vertices)");
    if (seen[v]) throw Error("reconstruction.anchors", "vertex " + std::to_string(v) + " is listed twice");
    seen[v] = 1;
    anchored[component[v]] = 1;
    out.push_back(v);
  }
  // Parts without anchors: one pinned vertex removes their translation null space.
  for (size_t c = 0; c < first_vertex.size(); ++c)
    if (!anchored[c]) out.push_back(first_vertex[c]);
  return out;
}

Reconstruction::Reconstruction(const Mesh& rest, ReconstructionOptions options, Prepared&& p)
    : options_(options),
      rest_(rest.vertices),
      edges_(std::move(p.topology.edges)),
      weight_(p.weight.data(), p.weight.data() + p.weight.size()),
      component_(std::move(p.components.component)),
      solver_(p.laplacian, pins(options, component_, p.components.first_vertex)) {
  options_.validate();
  const int parts = static_cast<int>(p.components.first_vertex.size());
  anchored_part_.assign(parts, 0);
  for (int v : options_.anchors) anchored_part_[component_[v]] = 1;
  rest_centroid_.assign(parts, Eigen::RowVector3d::Zero());
  component_size_.assign(parts, 0);
  for (int v = 0; v < rest_.rows(); ++v) {
    rest_centroid_[component_[v]] += rest_.row(v);
    ++component_size_[component_[v]];
  }
  for (int c = 0; c < parts; ++c) rest_centroid_[c] /= component_size_[c];
}

Positions Reconstruction::reconstruct(const float* features) const {
  const int n = vertex_count();
  std::vector<Eigen::Matrix3d> T(n);
  for (int i = 0; i < n; ++i) T[i] = unpack_dr(features + static_cast<size_t>(i) * kDrWidth);
  Rhs3 b = Rhs3::Zero(n, 3);
  for (size_t e = 0; e < edges_.size(); ++e) {
    const int i = edges_[e][0], j = edges_[e][1];
    const Eigen::RowVector3d d =
        (0.5 * weight_[e]) * ((T[i] + T[j]) * (rest_.row(i) - rest_.row(j)).transpose()).transpose();
    b.row(i) += d;
    b.row(j) -= d;
  }
  const std::vector<int>& pinned = solver_.pinned();
  Rhs3 pinned_values(pinned.size(), 3);
  for (size_t k = 0; k < pinned.size(); ++k) pinned_values.row(k) = rest_.row(pinned[k]);
  Rhs3 x;
  solver_.solve(b, pinned_values, x);

  // Each part without anchors keeps its rest centroid; its pinned vertex only removed the null
  // space. Anchored parts stay where their anchors hold them.
  std::vector<Eigen::RowVector3d> centroid(rest_centroid_.size(), Eigen::RowVector3d::Zero());
  for (int v = 0; v < n; ++v) centroid[component_[v]] += x.row(v);
  for (size_t c = 0; c < centroid.size(); ++c)
    centroid[c] = anchored_part_[c] ? Eigen::RowVector3d::Zero()
                                    : Eigen::RowVector3d(rest_centroid_[c] - centroid[c] / component_size_[c]);
  for (int v = 0; v < n; ++v) x.row(v) += centroid[component_[v]];

  if (!options_.parts) {
    if (options_.align_to_rest && options_.anchors.empty()) return rigid_alignment(x, rest_).apply(x);
    return x;
  }
  Positions out =
      options_.align_to_rest && options_.anchors.empty() ? rigid_alignment(x, rest_).apply(x) : Positions(x);
  options_.parts->apply(out);
  return out;
}

Positions Reconstruction::reconstruct(
    const Eigen::Ref<const Eigen::Matrix<float, Eigen::Dynamic, 9, Eigen::RowMajor>>& features) const {
  if (features.rows() != vertex_count())
    throw Error("reconstruction", "the features have " + std::to_string(features.rows()) +
                                      " rows but the rest mesh has " + std::to_string(vertex_count()) + " vertices");
  return reconstruct(features.data());
}

std::vector<Positions> Reconstruction::reconstruct_batch(const float* features, int count) const {
  std::vector<Positions> result(count);
  const size_t stride = static_cast<size_t>(vertex_count()) * kDrWidth;
  const int threads = options_.threads > 0 ? options_.threads : omp_get_max_threads();
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
  for (int b = 0; b < count; ++b) result[b] = reconstruct(features + b * stride);
  return result;
}

}  // namespace retarget
