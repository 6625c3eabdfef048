// The belief search (correspond/belief_search.h) over the rig head's map itself: one Gaussian
// belief over every entry of the linear map M (C controllers x S blendshapes,
// geometry/controller_map.h) from human blendshape weights to controller weights, so that each
// expression's controller weights are c_k = M r_k (r_k its recipe's blendshape weights). A
// comparison on one expression then teaches every expression that shares its shapes, and the
// belief's most likely map (likely_map) is a rig head that carries it to any blend. People who read a controller table
// their own way read it linearly too (a share of each shape), so the model is theirs.
//
// Shapes: the belief is over D = C * S numbers, entry (c, s) at index s * C + c; mean [D],
// covariance [D, D] float64; recipes are S-vectors in the map's shape order.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "correspond/belief_search.h"
#include "geometry/controller_map.h"

namespace retarget {

class MapBelief {
 public:
  // Around `prior` (its matrix is the mean), each entry with standard deviation prior_sd times
  // its controller's range. Throws retarget::Error for ranges that do not fit the map.
  MapBelief(const ControllerMap& prior, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
            const BeliefSearchOptions& options);

  // The belief over one expression's controller weights c = M r (r: S blendshape weights).
  Belief expression(const Eigen::VectorXd& recipe) const;
  // One decided comparison on the expression of `recipe`: `positive`'s face judged nearer, by
  // `annotator` (empty: unknown, or the tie-break; likely_map reads the answers of each named
  // annotator as one reading of the map).
  void observe(const Eigen::VectorXd& recipe, const Eigen::MatrixXd& metric, const Eigen::VectorXd& positive,
               const Eigen::VectorXd& negative, const std::string& annotator = "");
  // Expectation propagation over every answer observed so far, `passes` times: each answer's
  // factor (a rank-1 Gaussian along its cut, what observe() added) is taken out of the belief,
  // the answer is read again against that cavity and its factor replaced. One pass of observe()
  // is order-dependent (an early answer is read against the prior alone); refined, the belief
  // approaches the fixed point every order shares. A factor whose removal would leave no
  // proper belief is kept as it is. O(passes x answers x D^2).
  void refine(int passes);
  // The most informative pair for the expression of `recipe` (most_informative_pair).
  std::array<Eigen::VectorXd, 2> next_pair(const Eigen::VectorXd& recipe, const Eigen::MatrixXd& metric) const;
  // The map the belief bets on, with its covariance (pairs: the comparisons observed), as the rig
  // head uses it: the belief's most likely map with every entry inside its controller's range
  // (a shape at full weight moves a controller within it) and pulled towards the prior's by
  // options.sparsity (geometry/gaussian_box_mode.h: sparse_box_mode). The Gaussian alone leans
  // past a bound wherever answers only ever said "more" (a controller at its top), and spreads
  // what the references show together over every shape they share; both carry to blends.
  // With options.annotator_sd > 0 the map is the one the annotators share (teachings). With
  // options.leave_one_out each entry moves from the prior's no further than it does with any one
  // named annotator's answers left out, and not at all where leaving one out turns it back: what
  // one person alone says does not move the map. With options.jackknife_z > 0 each entry's move
  // shrinks by its jackknife spread over those leave-one-out readings (BeliefSearchOptions).
  ControllerMap likely_map() const;
  // The controllers no answer reached: every entry of the controller's row for a shape that the
  // observed expressions use still has at least `kept` of its prior standard deviation (none:
  // nothing observed). Its row in likely_map() stays near the prior's. The usual cause: the
  // controller barely moves the face beside the rest of an expression, so the search asks nothing
  // about it and no answer tells what it means
  // (docs/experiments/2026-11-29-what-the-annotators-cannot-see.md). kept in (0, 1].
  std::vector<std::string> unreached_controllers(double kept = 0.95) const;
  // Recipe weights by name -> an S-vector in the map's shape order (unknown names ignored).
  Eigen::VectorXd recipe_vector(const std::map<std::string, double>& weights) const;
  int observed() const { return observed_; }
  const Eigen::VectorXd& lower() const { return lower_; }
  const Eigen::VectorXd& upper() const { return upper_; }

 private:
  // One observed answer and the factor it contributes: precision tau and shift nu along
  // direction (the cut in map space, D), so the factor is exp(-tau (d'x)^2 / 2 + nu d'x).
  struct Site {
    Eigen::VectorXd recipe, positive, negative, direction;
    Eigen::MatrixXd metric;
    double tau = 0, nu = 0;
    std::string annotator;
  };
  // Moves the belief along a direction N (sigma_n = Sigma N) so that its projection there goes
  // from variance v and mean mu to v_to and mu_to: a rank-1 change.
  void shift_projection(const Eigen::VectorXd& sigma_n, double v, double mu, double v_to, double mu_to);
  // Reads one answer against the current belief and folds it in; returns its factor (no
  // direction when it teaches nothing: faces alike, or an update that is not finite).
  Site read_answer(const Eigen::VectorXd& recipe, const Eigen::MatrixXd& metric, const Eigen::VectorXd& positive,
                   const Eigen::VectorXd& negative, const std::string& annotator);
  // What each annotator's answers teach the map, in natural parameters: annotator -> (precision
  // [D, D], shift [D]) ("" for answers without one, which count as they are).
  using Teachings = std::map<std::string, std::pair<Eigen::MatrixXd, Eigen::VectorXd>>;
  // Each annotator's factors summed (L_a, h_a), or with options.annotator_sd > 0 what they teach the
  // map every annotator's reading varies about: their answers are evidence on their own map
  // M + E_a, E_a ~ N(0, R), R = diag((annotator_sd x range)^2), so what they teach M is precision
  // (L_a^-1 + R)^-1 = R^-1/2 B (I + B)^-1 R^-1/2 (B = R^1/2 L_a R^1/2) and shift
  // R^-1/2 (I + B)^-1 R^1/2 h_a. Many answers by one annotator then teach M no more than one
  // reading does. The shared map is the prior plus every annotator's teaching.
  Teachings teachings() const;
  // The reading of every answer in natural parameters (precision [D, D], shift [D]): the pooled
  // belief's, or with options.annotator_sd > 0 the prior's plus every annotator's teaching.
  void whole_reading(const Teachings& taught, Eigen::MatrixXd& precision, Eigen::VectorXd& shift) const;
  // How many of `annotator`'s answers the map (D, its faces inside the ranges) agrees with: the
  // positive's controller weights nearer its face than the negative's, in the answer's metric.
  int agreements(const Eigen::VectorXd& map, const std::string& annotator) const;
  // The reading that predicts held-out annotators best: with each of `names` left out in turn
  // (withouts: the pooled moves without them, from `start`, the prior inside the ranges), every
  // reading of the others' answers (pooled, and jackknifed at jackknife_z and at each of
  // jackknife_alternatives, the jackknife over leaving a second one out) scored by agreements()
  // on theirs. Returns the strength z with the highest total (0: pooled; the smaller z on a tie).
  double held_out_jackknife(
      const Teachings& taught, const Eigen::MatrixXd& precision, const Eigen::VectorXd& shift,
      const std::vector<std::string>& names, const std::vector<Eigen::VectorXd>& withouts, const Eigen::VectorXd& start,
      const std::function<Eigen::VectorXd(const Eigen::VectorXd&, const Eigen::MatrixXd&)>& mode_of) const;
  // The Gaussian of natural parameters (precision [D, D], shift [D]): its mean and covariance;
  // false where the precision is not positive definite (then they are not a proper belief).
  static bool gaussian_of(Eigen::MatrixXd precision, const Eigen::VectorXd& shift, Eigen::VectorXd& mean,
                          Eigen::MatrixXd& covariance);

  ControllerMap prior_;
  std::vector<Site> sites_;
  Eigen::VectorXd lower_, upper_;
  BeliefSearchOptions options_;
  Eigen::VectorXd prior_variance_;  // D: the prior's (diagonal) covariance
  Eigen::VectorXd mean_;            // D
  Eigen::MatrixXd covariance_;      // D x D
  int observed_ = 0;
};

}  // namespace retarget
