// Deformation representation (DR) features: per vertex, the rotation and the stretch that
// carry the rest mesh's one-ring onto the deformed mesh's (Gao et al.; method notes).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "geometry/cotangent_weights.h"
#include "geometry/mesh.h"
#include "geometry/mesh_topology.h"

namespace retarget {

// Layout of the 9 floats of one vertex, fixed for the whole project:
//   [0..2] log R as a rotation vector (axis * angle, radians),
//   [3..8] S - I, upper triangle row by row: (S00-1, S01, S02, S11-1, S12, S22-1).
// The rest pose is all zeros.
constexpr int kDrWidth = 9;
using DrFeatureMatrix = Eigen::Matrix<float, Eigen::Dynamic, kDrWidth, Eigen::RowMajor>;  // #V x 9

// Packs T = R S (R rotation, S symmetric) into 9 floats; unpack returns exp(log R) (S).
void pack_dr(const Eigen::Matrix3d& R, const Eigen::Matrix3d& S, float* out9);
Eigen::Matrix3d unpack_dr(const float* in9);

struct DrOptions {
  EdgeWeighting weighting = EdgeWeighting::cotangent;  // uniform: the authors' second variant
  // Adds the vertex normal, scaled by the one-ring's mean edge length, as one more
  // weighted "edge". Flat one-rings then have a well-defined gradient (the plain fit is
  // rank 2 there), a rigid motion still gives T = R and a uniform scale T = s I exactly.
  bool normal_term = true;
  // Weight of that normal "edge" relative to the one-ring's mean edge weight. Small, so
  // that it decides only what the edges leave open (a flat one-ring's normal direction)
  // and does not bias the in-plane fit that reconstruction relies on.
  double normal_weight = 1e-4;
  int threads = 0;        // OpenMP threads; 0 = the OpenMP default (all cores)
  void validate() const;  // throws retarget::Error naming the option
};

// Precomputes everything that depends on the rest mesh only (weights, rest edges, the
// inverse of each vertex's rest covariance), so each deformed mesh costs one pass.
class DrFeatures {
 public:
  // rest: the rest mesh (its triangles define the one-rings), positions in any unit.
  explicit DrFeatures(const Mesh& rest, DrOptions options = {});

  int vertex_count() const { return vertex_count_; }
  const DrOptions& options() const { return options_; }

  // deformed: #V x 3, same vertex order as the rest mesh. out: #V x 9 floats.
  // Parallel over vertices; results do not depend on the thread count.
  void compute(const Positions& deformed, float* out) const;
  DrFeatureMatrix compute(const Positions& deformed) const;

  // B deformed meshes -> out: B x #V x 9 floats, contiguous ([B, V, 9] float32).
  // Parallel over meshes (or over vertices when B is small).
  void compute_batch(const std::vector<const Positions*>& deformed, float* out) const;

  // The per-vertex deformation gradient T_i (before the polar decomposition), for tests.
  Eigen::Matrix3d deformation_gradient(const Positions& deformed, int vertex) const;

 private:
  // Area-weighted triangle normals (#T) of a deformed mesh, for triangles [begin, end).
  void triangle_normals(const Positions& deformed, int begin, int end, Eigen::Vector3d* out) const;
  // Writes vertices [begin, end) of one mesh given its triangle normals.
  void compute_range(const Positions& deformed, const Eigen::Vector3d* normals, int begin, int end, float* out) const;
  Eigen::Vector3d vertex_normal(const Eigen::Vector3d* normals, int vertex) const;
  Eigen::Matrix3d gradient(const Positions& deformed, const Eigen::Vector3d* normals, int vertex) const;
  int threads() const;

  DrOptions options_;
  int vertex_count_ = 0;
  Triangles triangles_;
  CompressedRows neighbors_;                           // one-ring of each vertex
  CompressedRows incident_;                            // triangles around each vertex
  std::vector<double> weight_;                         // per neighbor entry: w_ij
  std::vector<Eigen::Vector3d> weighted_rest_edge_;    // per neighbor entry: w_ij e_ij
  std::vector<double> weight_sum_;                     // per vertex: sum_j w_ij
  std::vector<Eigen::Vector3d> weighted_rest_normal_;  // per vertex: w_n l_i n_i (zero if unused)
  std::vector<Eigen::Matrix3d> rest_inverse_;          // per vertex: (sum w e e^T + w_n l^2 n n^T)^+
};

}  // namespace retarget
