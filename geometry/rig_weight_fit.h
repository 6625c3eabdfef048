// Controller weights that reproduce a mesh on a rig: the bounded least-squares fit
//   w* = argmin_{lo_c <= w_c <= hi_c}  |sum_c w_c offset_c - (deformed - neutral)|^2
//                                      + ridge s |w|^2 + smoothness s |w - w_previous|^2
// over every vertex and coordinate, where s is the mean diagonal of the offsets' Gram matrix (the
// mean squared norm of a controller's offset), so that both terms are scale-free: the same value
// means the same on any rig, in any unit. Prefactored once per rig (the Gram matrix and the
// offsets' products with the neutral), then solved by projected coordinate descent on the normal
// equations (rigs have tens of controllers); a fit allocates nothing of the mesh's size.
//   - the ridge pulls every weight towards 0 (the neutral): the regulariser against implausible
//     combinations, near-collinear controllers driven far in opposite directions to cancel;
//   - the smoothness term pulls towards the previous frame's weights (fit(deformed, previous)):
//     for sequences, against frame-to-frame jitter where the mesh leaves the weights ambiguous.
// Used to score outputs in rig-weight space (eval/retarget_evaluation.h), to project
// deformation-transfer results onto the rig's own expressions (correspond/correspondence.h) and
// to write controller weights at inference (infer/weights_output.h).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "geometry/rig.h"

namespace retarget {

struct RigWeightFitOptions {
  double ridge = 0;         // >= 0, times the mean diagonal of the Gram matrix (scale-free)
  double smoothness = 0;    // >= 0, likewise; used only by fits given the previous frame's weights
  int sweeps = 500;         // coordinate-descent sweeps at most, >= 1
  double tolerance = 1e-9;  // stop when no weight changed by more than this in a sweep, > 0
  void validate() const;    // throws retarget::Error naming the field
};

class RigWeightFit {
 public:
  // Keeps a reference to `rig`: it must outlive the fit.
  explicit RigWeightFit(const Rig& rig, RigWeightFitOptions options = {});

  // deformed: #V x 3 in the rig's frame and units (no alignment is done here). Returns
  // #controllers weights, each within its controller's range (the ridge applies, the smoothness
  // term does not). Throws retarget::Error for a vertex count other than the rig's.
  Eigen::VectorXd fit(const Positions& deformed) const;

  // The same with the smoothness term towards `previous` (#controllers weights, e.g. the last
  // frame's fit; the descent starts there). An empty `previous` (a sequence's first frame) gives
  // fit(deformed). Throws retarget::Error for a size other than #controllers.
  Eigen::VectorXd fit(const Positions& deformed, const Eigen::VectorXd& previous) const;

  // The rig evaluated at fit(deformed): the nearest expression the rig itself can make.
  Positions project(const Positions& deformed) const;

  // Mean distance over moving_vertices() between `deformed` (#V x 3) and the rig evaluated at
  // `weights` (#controllers), in the rig's units; 0 when the rig moves nothing. Allocates nothing
  // of the mesh's size.
  double residual(const Positions& deformed, const Eigen::VectorXd& weights) const;

  // The vertices some controller moves: those whose largest displacement at either end of a
  // controller's range exceeds 1% of the rig's largest (geometry/rig_footprint.h's floor).
  // Ascending.
  const std::vector<int>& moving_vertices() const { return moving_; }

  const Rig& rig() const { return rig_; }
  const RigWeightFitOptions& options() const { return options_; }

 private:
  void check_vertices(const Positions& deformed) const;

  const Rig& rig_;
  RigWeightFitOptions options_;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> basis_;  // 3V x C, row 3v + a
  Eigen::MatrixXd gram_;           // C x C, with the ridge on its diagonal
  Eigen::VectorXd basis_neutral_;  // C: basis^T neutral (so that a fit needs no mesh-sized difference)
  double scale_ = 0;               // mean diagonal of basis^T basis (before the ridge)
  std::vector<int> moving_;
};

}  // namespace retarget
