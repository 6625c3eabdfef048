// DR features -> vertex positions, by the weighted least-squares system of the method
// notes, factorised once per rest mesh.
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "geometry/cotangent_weights.h"
#include "geometry/mesh.h"
#include "geometry/sparse_cholesky.h"

namespace retarget {

class PartMotion;

struct ReconstructionOptions {
  // Must match the weighting the features were computed with (DrOptions::weighting).
  EdgeWeighting weighting = EdgeWeighting::cotangent;
  // false: every connected part keeps its rest centroid (features carry no translation).
  // true: the result is then rigidly aligned (rotation + translation) to the rest pose,
  // as the authors' code did. Ignored with anchors: they already hold the rest's frame.
  bool align_to_rest = false;
  // Vertices held at their rest positions: the region a dataset never moves (the back of a
  // head, a neck). Without anchors a part is free to integrate every small feature error over
  // its whole extent (a low-frequency drift that grows with the mesh); anchored, errors stay
  // where the features are wrong and the still region is exact. A part with anchors keeps them
  // instead of its rest centroid. Indices in [0, #V), no duplicates.
  std::vector<int> anchors;
  int threads = 0;  // OpenMP threads for batches; 0 = the OpenMP default
  // An avatar's rigid parts moved where its rig puts them (geometry/part_motion.h), after the
  // alignment to the rest pose; null: each part stays at its rest centroid. Must be built for
  // this rest mesh's rig (same vertex count).
  std::shared_ptr<const PartMotion> parts;
  void validate() const;
};

// Minimises sum_ij w_ij |(p_i - p_j) - 1/2 (T_i + T_j)(q_i - q_j)|^2 over p, q the rest
// positions and T_i = exp(log R_i) S_i from the features. The matrix is the weighted
// Laplacian of the rest mesh: it is factorised in the constructor (one vertex pinned per
// connected part, which removes the translation null space) and each frame costs one
// right-hand side and one solve.
class Reconstruction {
 public:
  explicit Reconstruction(const Mesh& rest, ReconstructionOptions options = {});

  int vertex_count() const { return static_cast<int>(rest_.rows()); }

  // features: #V x 9 floats in the DrFeatures layout. Returns #V x 3 in the rest's units.
  Positions reconstruct(const float* features) const;
  Positions reconstruct(
      const Eigen::Ref<const Eigen::Matrix<float, Eigen::Dynamic, 9, Eigen::RowMajor>>& features) const;

  // features: B x #V x 9 contiguous; parallel over frames. Returns B meshes.
  std::vector<Positions> reconstruct_batch(const float* features, int count) const;

  long factor_nonzeros() const { return solver_.factor_nonzeros(); }

 private:
  struct Prepared;
  static Prepared prepare(const Mesh& rest, EdgeWeighting weighting);
  // The solver's pinned vertices: the anchors, plus one vertex of each part without any.
  // component: the part of each vertex (#V); first_vertex: one vertex per part.
  static std::vector<int> pins(const ReconstructionOptions& options, const std::vector<int>& component,
                               const std::vector<int>& first_vertex);
  Reconstruction(const Mesh& rest, ReconstructionOptions options, Prepared&& prepared);

  ReconstructionOptions options_;
  Positions rest_;
  std::vector<std::array<int, 2>> edges_;
  std::vector<double> weight_;
  std::vector<int> component_;                     // #V
  std::vector<char> anchored_part_;                // per connected part: held by anchors (no centroid shift)
  std::vector<Eigen::RowVector3d> rest_centroid_;  // per connected part
  std::vector<int> component_size_;
  PinnedCholesky solver_;
};

}  // namespace retarget
