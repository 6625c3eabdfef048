// Learning the rig head's map (geometry/controller_map.h) from what the annotators chose: the
// champions' pairs in closed form (ridge towards a prior map), every decided comparison through a
// logistic loss in the rig's face metric (LibTorch), and how far to trust the prior, chosen by
// cross-validation over the expressions.
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "geometry/controller_map.h"

namespace retarget {

struct ControllerMapOptions {
  double prior_weight = 1.0;  // ridge towards the prior map (towards 0 without one), per pair; >= 0
  void validate(const std::string& key_path = "controller_map") const;
};

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

}  // namespace retarget
