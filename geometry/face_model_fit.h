// A face's expression as the face model's blendshape weights: the human side of the controller
// map (geometry/controller_map.h), as a tracker gives ARKit weights. The model is linear
// (geometry/face_model.h: person = neutral + sum c_i identity_i, expression = person + sum w_j
// expression_j), so the weights of a face of an unknown person are a bounded least-squares fit:
//   min over c (free) and w in [lo, hi] of |face - neutral - I c - E w|^2 (+ ridge |w|^2),
// the identity eliminated by projecting it out. The projected Gram matrix is built once per model
// and factorised; the box-constrained problem starts from the clamped unconstrained solution and
// is finished by coordinate descent on it, so a fit costs #V x #E
// multiply-adds (E^T Q d) plus #E^2 per sweep.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

#include "geometry/face_model.h"

namespace retarget {

struct FaceFitOptions {
  double lo = 0.0, hi = 1.0;  // each weight's bounds
  double ridge = 1e-6;        // times the mean diagonal of the Gram matrix, towards 0; >= 0
  int sweeps = 500;           // coordinate-descent sweeps at most; >= 1
  double tolerance = 1e-9;    // stop when no weight moves more than this in a sweep
  void validate(const std::string& key_path = "face_fit") const;
};

class FaceModelFit {
 public:
  // Throws retarget::Error for a model without expression shapes or bad options.
  explicit FaceModelFit(const FaceModel& model, const FaceFitOptions& options = {});

  // face: #V x 3 in the model's frame and units (no rigid motion is removed). Returns one weight
  // per model expression shape, by name. Throws retarget::Error when the vertex count differs.
  std::map<std::string, double> fit(const Positions& face) const;

  const std::vector<std::string>& shapes() const { return shapes_; }

 private:
  FaceFitOptions options_;
  std::vector<std::string> shapes_;
  Eigen::MatrixXd neutral_;              // #V x 3, flattened on use
  Eigen::MatrixXd projected_;            // (3V) x E: Q E, Q the projection off the identity modes
  Eigen::MatrixXd gram_;                 // E x E: E^T Q E (+ ridge)
  Eigen::LDLT<Eigen::MatrixXd> solver_;  // of gram_, factorised once
};

}  // namespace retarget
