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
#include "geometry/rig.h"

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

// human: K blendshape weight maps; controller_weights: K x C. Row c of the map solves
//   min_m sum_k (m . r_k - y_kc)^2 + prior_weight * K / S * |m - p_c|^2
// (p_c the prior's row, 0 without one). Throws retarget::Error for mismatched sizes.
ControllerMap fit_controller_map(const std::vector<std::map<std::string, double>>& human,
                                 const Eigen::MatrixXd& controller_weights, const std::vector<std::string>& controllers,
                                 const std::vector<std::string>& shapes, const ControllerMap* prior,
                                 const ControllerMapOptions& options = {});

// One annotated comparison in weights: for the human expression `human`, the avatar expression
// with controller weights `positive` was judged closer than the one with `negative`.
struct RankedPair {
  std::map<std::string, double> human;
  Eigen::VectorXd positive, negative;  // C each
};

struct RankingOptions {
  double prior_weight = 1.0;     // ridge towards the prior map, against the mean losses below; >= 0
  double champion_weight = 1.0;  // the champions' squared error, beside the comparisons'; >= 0
  int steps = 400;               // Adam steps; >= 1
  double lr = 0.02;              // Adam's learning rate; > 0
  void validate(const std::string& key_path = "ranking") const;
};

// The map that makes every comparison count, not only each tournament's winner: it minimises
//   champion_weight * mean_k |M r_k - y_k|^2_G + mean_t tau * log(1 + exp((d_t+ - d_t-) / tau))
//   + prior_weight * |M - P|^2_F / S
// with d_t+- = |M r_t - y_t+-|^2_G, the distances in the metric G (C x C, e.g. the rig's offsets'
// Gram matrix over its moving vertices: distances between the faces, not the weights) and tau the
// median |d_t+ - d_t-| at the prior (the comparisons' own scale). A noisy answer costs little; a
// preference the annotators keep stating moves the map. `champions`/`controller_weights` as for
// fit_controller_map (either may be empty). Throws retarget::Error for mismatched sizes.
ControllerMap fit_controller_map_ranked(const std::vector<std::map<std::string, double>>& champions,
                                        const Eigen::MatrixXd& controller_weights,
                                        const std::vector<RankedPair>& comparisons, const Eigen::MatrixXd& metric,
                                        const std::vector<std::string>& controllers,
                                        const std::vector<std::string>& shapes, const ControllerMap& prior,
                                        const RankingOptions& options = {});

// How much to trust the prior, chosen by the annotators themselves: for each weight of `grid`
// (and the prior alone, weight +inf), the map is fitted with the comparisons and champions of all
// but one of `folds` groups of expressions and scored by how many comparisons of the held-out
// expressions it agrees with (the positive nearer its prediction than the negative, in the
// metric). The largest weight within one standard error (sqrt(p (1 - p) / n) of the best
// agreement p over n held-out comparisons) of the best wins: a correction must beat the prior by
// more than the comparisons' own noise. A prior the annotators confirm is kept; corrections they
// make consistently across expressions are taken.
struct PriorWeightChoice {
  double weight = 1;                                 // the chosen weight (+inf: the prior alone)
  std::vector<std::pair<double, double>> agreement;  // (weight, held-out agreement in [0, 1])
};
PriorWeightChoice choose_prior_weight(const std::vector<std::map<std::string, double>>& champions,
                                      const Eigen::MatrixXd& controller_weights,
                                      const std::vector<RankedPair>& comparisons, const Eigen::MatrixXd& metric,
                                      const std::vector<std::string>& controllers,
                                      const std::vector<std::string>& shapes, const ControllerMap& prior,
                                      const RankingOptions& options,
                                      const std::vector<double>& grid = {0.1, 1, 10, 100}, int folds = 4);

void write_controller_map(const std::string& path, const ControllerMap& map);  // atomically
// Throws retarget::Error naming file:line and key for anything malformed.
ControllerMap load_controller_map(const std::string& path);

}  // namespace retarget
