// Controller weights that reproduce a mesh on a rig: the bounded least-squares fit
//   w* = argmin_{lo_c <= w_c <= hi_c} |sum_c w_c offset_c - (deformed - neutral)|^2 + ridge |w|^2
// over every vertex and coordinate, prefactored once per rig (the offsets' Gram matrix), then
// solved by projected coordinate descent on the normal equations (rigs have tens of
// controllers). Used to score outputs in rig-weight space (eval/retarget_evaluation.h) and to
// project deformation-transfer results onto the rig's own expressions (correspond/correspondence.h).
#pragma once

#include <Eigen/Core>

#include "geometry/rig.h"

namespace retarget {

struct RigWeightFitOptions {
  double ridge = 0;         // >= 0, times the mean diagonal of the Gram matrix (scale-free)
  int sweeps = 500;         // coordinate-descent sweeps at most, >= 1
  double tolerance = 1e-9;  // stop when no weight changed by more than this in a sweep, > 0
  void validate() const;    // throws retarget::Error naming the field
};

class RigWeightFit {
 public:
  // Keeps a reference to `rig`: it must outlive the fit.
  explicit RigWeightFit(const Rig& rig, RigWeightFitOptions options = {});

  // deformed: #V x 3 in the rig's frame and units (no alignment is done here). Returns
  // #controllers weights, each within its controller's range. Throws retarget::Error for a
  // vertex count other than the rig's.
  Eigen::VectorXd fit(const Positions& deformed) const;

  // The rig evaluated at fit(deformed): the nearest expression the rig itself can make.
  Positions project(const Positions& deformed) const;

  const Rig& rig() const { return rig_; }

 private:
  const Rig& rig_;
  RigWeightFitOptions options_;
  Eigen::MatrixXd basis_;  // 3V x C, row 3v + a
  Eigen::MatrixXd gram_;   // C x C, with the ridge on its diagonal
};

}  // namespace retarget
