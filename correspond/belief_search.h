// Choosing each comparison for the most it can teach (the paper's future work, beyond its fixed
// tournaments): per human expression, a Gaussian belief over the rig weights c* the annotators
// mean, updated by each decided comparison, and the next pair of candidates placed where the
// belief is least sure.
//
// Model. The rig is linear in its controllers (geometry/rig.h), so with G the Gram matrix of
// its offsets over the moving vertices (correspond/rig_face_metric.h), the squared distance
// between the faces of weights a and c is |a - c|^2_G. An annotator who judges a nearer than
// b to the face they read into the human expression answers, in effect, the sign of
//   s(c*) = |b - c*|^2_G - |a - c*|^2_G = b'Gb - a'Ga - 2 c*'G (b - a),
// which is linear in c*: every comparison is a cut of weight space by a hyperplane. People's
// perception is relative (Weber): a judged distance d carries noise of about weber * d, so with
// d_a, d_b the two distances, P(a) = Phi((d_b - d_a) / (sqrt(2) weber (d_a + d_b) / 2)) =
// Phi(s / T), T = weber (d_a + d_b)^2 / sqrt(2), the distances taken at the belief (mean plus
// its spread). Annotators also read the avatar each their own way (their c* differs by about
// reading_sd of each range: T grows by that variance of s) and lapse (a random answer with
// probability lapse). Each answer updates the belief by assumed-density filtering (the Gaussian
// whose mean and covariance match the exact posterior's), in closed form.
//
// Choice. Candidate pairs are the belief's mode inside the ranges +- a step along each
// direction of uncertainty in face space (the generalised eigenvectors of G S G u = lambda G u,
// S the covariance of the belief truncated to the ranges: where its spread moves the face most),
// at step, step / 2 and step / 4 standard deviations along it, clamped into the ranges; the pair
// whose answer is expected to tell the most about c* wins (BALD, Houlsby et al. 2011: the
// entropy of the predicted answer less its expected entropy given c*). A pair's hyperplane
// passes near the mode, across the direction the belief knows least: noisy bisection, which
// asks nothing the belief already knows and nothing outside what the rig can make.
//
// Shapes: weights and means are C-vectors (C = the rig's controllers), covariances and G C x C,
// all float64, in the controllers' own units.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace retarget {

struct BeliefSearchOptions {
  double prior_sd = 0.5;  // the belief's prior standard deviation, a fraction of each controller's range; > 0
  // The map belief's prior spread of an entry the prior map leaves at 0 in a row it does not
  // leave empty (a shape the controller, read as others, does not listen to), as a fraction of
  // prior_sd; in (0, 1]; empty rows keep prior_sd. Below 1 the search spends fewer answers on
  // ruling out what the table already rules out (a jaw that a pucker might open) and more on
  // the table's shares; it also learns more slowly what the table missed. Measured at 0.3 (as
  // the search's prior and as the rig head's reading): the synthetic fox gains a little, the
  // real rabbit, whose table is poor, loses a third of what the annotators taught it
  // (docs/experiments/2026-11-29-the-tables-zeros.md). 1: every entry alike.
  double off_table = 1.0;
  double weber = 0.1;  // assumed perception noise, a fraction of a judged distance; > 0
  // Assumed spread of annotators' readings, a fraction of each range; >= 0. Wider than one
  // reading's own spread: an annotator answers many comparisons with the same reading, so
  // their answers are less independent than the update counts them (docs/results.md).
  double reading_sd = 0.25;
  double lapse = 0.05;  // assumed probability of a random answer; in [0, 0.5)
  double step = 2.0;    // half the gap between a pair, in the belief's sds along its direction; > 0
  // The map's reading (correspond/map_belief.h): a Laplace pull of each entry towards the
  // prior's, per unit of its controller's range (a controller listens to few shapes: an entry
  // moves only where the evidence outweighs it); 0: the plain mode inside the ranges. >= 0
  double sparsity = 2.0;
  // Passes of expectation propagation over the observed answers before the map is read
  // (MapBelief::refine): each answer is taken back out and read again against everything the
  // others taught, so the map no longer depends on the order the answers came in. 0: the
  // one-pass belief the search itself keeps. >= 0
  int refine_passes = 0;
  // The map's reading (MapBelief::likely_map): each annotator reads the map their own way, about
  // the map they all share, by this spread (a fraction of each controller's range): many answers
  // of one annotator teach the shared map no more than one reading. 0: every answer pooled, as
  // from one reader. >= 0
  double annotator_sd = 0;
  // The map's reading (MapBelief::likely_map): each entry moves from the prior's only as far as it
  // does with any one annotator's answers left out: what one person alone says moves nothing.
  // Measured: mends a trusted table's misreadings (the synthetic fox and bramble) and loses what
  // the annotators teach a poor one (the rabbit's): docs/experiments/2026-11-28-the-map-people-share.md.
  bool leave_one_out = false;
  // The map's reading (MapBelief::likely_map): each entry's move from the prior's is shrunk by how
  // much it depends on who answered: read again with each annotator's answers left out in turn,
  // the moves' jackknife variance V gives the move m a factor max(0, 1 - z^2 V / m^2) (z this
  // setting). A move every annotator makes stays whole; one a few of them make shrinks to the
  // prior's. 0: off. >= 0; leave_one_out, when set, replaces it.
  double jackknife_z = 0;
  // With jackknife_z > 0 (ignored at 0, the pooled map): the jackknifed map only where it
  // predicts held-out annotators better.
  // Each named annotator in turn is left out; both readings (pooled, jackknifed) are made from the
  // others' answers and scored on how many of theirs the map's faces agree with; the reading with
  // more agreements over all annotators is the map's. A trusted table a few misread keeps the
  // jackknife; a poor one whose moves the annotators share keeps the pooled map.
  bool jackknife_if_it_predicts = false;
  // With jackknife_if_it_predicts: further strengths z tried beside jackknife_z. Every reading
  // (pooled, and jackknifed at each z) is scored the same way on the held-out annotators; the one
  // that agrees with the most of their answers is the map's, the weaker shrinkage on a tie (pooled
  // first). Each >= 0; scoring one more z costs only the agreements (the readings without one and
  // two annotators are made once). Empty: pooled against jackknife_z alone.
  std::vector<double> jackknife_alternatives;
  // Throws retarget::Error naming `key_path`.<field> for a value out of range.
  void validate(const std::string& key_path = "correspond.belief") const;
  // The rig head's reading of the answers (`retarget rig-map fit --belief`, RigHeadFitOptions):
  // these defaults with 3 passes of expectation propagation and readings assumed at 0.35 of a
  // range. Refined, every answer counts in full against all the others (the search's one pass
  // reads early answers against the prior alone, which damps them), so the readings' spread
  // widens by as much: each annotator answers many comparisons with one reading, and what three
  // annotators share is not the table (docs/experiments/2026-11-28-annotators-who-keep-their-reading.md).
  // The map is jackknifed (the empirical-Bayes shrinkage of each entry's move, at z 1 or 2)
  // where that predicts held-out annotators' answers better than the pooled map, else pooled; of
  // the two strengths, the one that predicts them better
  // (docs/experiments/2026-11-29-the-reading-held-out-people-predict.md,
  // docs/experiments/2026-11-29-how-hard-to-jackknife.md).
  static BeliefSearchOptions map_reading();
};

struct Belief {
  Eigen::VectorXd mean;        // C
  Eigen::MatrixXd covariance;  // C x C, symmetric positive definite
};

// The prior around `start` (C, e.g. what a controller table reads into the expression):
// covariance diag((prior_sd * (upper - lower))^2). Throws retarget::Error for sizes that differ
// or a range that is empty.
Belief prior_belief(const Eigen::VectorXd& start, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                    const BeliefSearchOptions& options);

// What one decided comparison says about x = n'c + offset (header), under `belief`: the
// moment-matched update is mean += Sigma n * gain, Sigma += (Sigma n)(Sigma n)' * curvature.
// `n` is empty when the two faces do not differ (the answer teaches nothing).
struct CutUpdate {
  Eigen::VectorXd n;     // C
  double gain = 0;       // d log P(answer) / d m, m the belief's mean of x
  double curvature = 0;  // d^2 log P(answer) / d m^2 (negative: the belief narrows)
};
CutUpdate comparison_update(const Belief& belief, const Eigen::MatrixXd& metric, const Eigen::VectorXd& positive,
                            const Eigen::VectorXd& negative, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                            const BeliefSearchOptions& options);

// One decided comparison: the face of `positive` was judged nearer than that of `negative`.
// `metric` is G (C x C). A pair whose faces do not differ teaches nothing and leaves the belief
// as it was. Throws retarget::Error for sizes that differ.
void observe(Belief& belief, const Eigen::MatrixXd& metric, const Eigen::VectorXd& positive,
             const Eigen::VectorXd& negative, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
             const BeliefSearchOptions& options);

// The pair with the most expected information (above), each inside [lower, upper]; the two are
// the same only when the belief is certain.
std::array<Eigen::VectorXd, 2> most_informative_pair(const Belief& belief, const Eigen::MatrixXd& metric,
                                                     const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                                                     const BeliefSearchOptions& options);

// The rig weights the belief bets on: its mode inside the ranges (correspond/belief_box.h).
Eigen::VectorXd belief_estimate(const Belief& belief, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper);

}  // namespace retarget
