// The rig head's map: a linear map from human blendshape weights to the avatar's controller
// weights, learnt from what the annotators chose (correspond/controller_map_fit.h); applied here,
// by `retarget rig-map apply` and by retarget-infer --rig-map. Each tournament's champion is a rig expression with
// known controller weights, and its human expression a recipe with known blendshape weights; the
// map is fitted to those pairs, ridge-regularised towards a prior map (a controller table, e.g.
// the one `avatar meaning` proposes with no person involved). Rigs and face models are linear
// in their weights, so what the annotators taught on 47 references carries to any blend of the
// same shapes; outputs stay on the rig (clamped to each controller's range), like DT on the rig.
//
// map.yaml:
//   format: retarget-controller-map
//   controllers: [smileLeft, ...]      # C, the rig's order
//   shapes: [jawOpen, ...]             # S, the face model's order
//   matrix: [[...S numbers...], ...]   # C rows
//   pairs: 47                          # annotated pairs it was fitted to (0: the prior alone)
//   prior: /abs/table.yaml             # the prior's source ("" for none)
//   covariance: map.yaml.covariance.pt # optional, beside the map: the uncertainty of the
//                                      # matrix (the belief search's, correspond/map_belief.h),
//                                      # tensor "covariance" [C*S, C*S] float64, entry (c, s) at
//                                      # s * C + c. With it a face is read as the most likely
//                                      # controller weights inside the rig's ranges
//                                      # (geometry/gaussian_box_mode.h), not the clamped product.
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

#include "geometry/controller_correspondence.h"
#include "geometry/rig.h"

namespace retarget {

struct ControllerMap {
  std::vector<std::string> controllers;  // C
  std::vector<std::string> shapes;       // S
  Eigen::MatrixXd matrix;                // C x S
  int pairs = 0;
  std::string prior;
  Eigen::MatrixXd covariance;  // [C*S, C*S] (entry (c, s) at s * C + c); empty: none

  // The map's reading of blendshape weights r (S, the map's order): M r, and with a covariance
  // its covariance R' Sigma R (C x C, R = r (x) I_C).
  Eigen::VectorXd mean_of(const Eigen::VectorXd& r) const { return matrix * r; }
  Eigen::MatrixXd covariance_of(const Eigen::VectorXd& r) const;

  // Controller weights (C, the map's order) for blendshape weights by name (unknown names are
  // ignored), inside [lo, hi] per controller when given (the rig's ranges): clamped, or with a
  // covariance its most likely point there.
  Eigen::VectorXd apply(const std::map<std::string, double>& weights, const Eigen::VectorXd& lo = {},
                        const Eigen::VectorXd& hi = {}) const;
  // apply() for `rig`: the map's controllers must be the rig's, in its order (else
  // retarget::Error naming both counts and `where`), each weight clamped to its range.
  Eigen::VectorXd on_rig(const std::map<std::string, double>& weights, const Rig& rig,
                         const std::string& where = "controller map") const;
};

// True when the YAML file at `path` is a controller map (format: retarget-controller-map), false
// for anything else (e.g. a controller table). Throws retarget::Error when it does not parse.
bool is_controller_map_file(const std::string& path);

// The prior map of a controller table: column s is controller_weights_from_human(table, {s: 1})
// without clamping (the table's least-squares reading is linear in the human weights).
ControllerMap controller_map_from_table(const ControllerCorrespondence& table,
                                        const std::vector<std::string>& controllers,
                                        const std::vector<std::string>& shapes);

// The map a prior file gives: a controller map (checked against `controllers` and `shapes`) or a
// controller table read linearly (controller_map_from_table; its `prior` the table's absolute
// path). Throws retarget::Error naming the file for one that does not fit.
ControllerMap load_prior_map(const std::string& path, const std::vector<std::string>& controllers,
                             const std::vector<std::string>& shapes);

// Atomically; with a covariance also `path`.covariance.pt.
void write_controller_map(const std::string& path, const ControllerMap& map);
// Throws retarget::Error naming file:line and key for anything malformed.
ControllerMap load_controller_map(const std::string& path);

}  // namespace retarget
