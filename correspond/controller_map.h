// The rig head: a linear map from human blendshape weights to the avatar's controller weights,
// learnt from what the annotators chose. Each tournament's champion is a rig expression with
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
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

#include "geometry/controller_correspondence.h"

namespace retarget {

struct ControllerMapOptions {
  double prior_weight = 1.0;  // ridge towards the prior map (towards 0 without one), per pair; >= 0
  void validate(const std::string& key_path = "controller_map") const;
};

struct ControllerMap {
  std::vector<std::string> controllers;  // C
  std::vector<std::string> shapes;       // S
  Eigen::MatrixXd matrix;                // C x S
  int pairs = 0;
  std::string prior;

  // Controller weights (C, the map's order) for blendshape weights by name (unknown names are
  // ignored), clamped to [lo, hi] per controller when given (the rig's ranges).
  Eigen::VectorXd apply(const std::map<std::string, double>& weights, const Eigen::VectorXd& lo = {},
                        const Eigen::VectorXd& hi = {}) const;
};

// The prior map of a controller table: column s is controller_weights_from_human(table, {s: 1})
// without clamping (the table's least-squares reading is linear in the human weights).
ControllerMap controller_map_from_table(const ControllerCorrespondence& table,
                                        const std::vector<std::string>& controllers,
                                        const std::vector<std::string>& shapes);

// human: K blendshape weight maps; controller_weights: K x C. Row c of the map solves
//   min_m sum_k (m . r_k - y_kc)^2 + prior_weight * K / S * |m - p_c|^2
// (p_c the prior's row, 0 without one). Throws retarget::Error for mismatched sizes.
ControllerMap fit_controller_map(const std::vector<std::map<std::string, double>>& human,
                                 const Eigen::MatrixXd& controller_weights, const std::vector<std::string>& controllers,
                                 const std::vector<std::string>& shapes, const ControllerMap* prior,
                                 const ControllerMapOptions& options = {});

void write_controller_map(const std::string& path, const ControllerMap& map);  // atomically
// Throws retarget::Error naming file:line and key for anything malformed.
ControllerMap load_controller_map(const std::string& path);

}  // namespace retarget
