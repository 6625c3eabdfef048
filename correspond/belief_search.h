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
// Choice. The next pair is mean +- step * sd along the direction u of largest uncertainty in
// face space (the top generalised eigenvector of G Sigma G u = lambda G u: where the belief's
// spread moves the face most), sd the belief's standard deviation along u, each clamped into
// the controllers' ranges. Its hyperplane passes through the mean, perpendicular (in G) to the
// direction the belief knows least: the cut with the most expected information, as bisection
// in one dimension.
//
// Shapes: weights and means are C-vectors (C = the rig's controllers), covariances and G C x C,
// all float64, in the controllers' own units.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>

namespace retarget {

struct BeliefSearchOptions {
  double prior_sd = 0.5;     // the belief's prior standard deviation, a fraction of each controller's range; > 0
  double weber = 0.1;        // assumed perception noise, a fraction of a judged distance; > 0
  double reading_sd = 0.08;  // assumed spread of annotators' readings, a fraction of each range; >= 0
  double lapse = 0.05;       // assumed probability of a random answer; in [0, 0.5)
  double step = 2.0;         // half the gap between a pair, in the belief's sds along its direction; > 0
  // Throws retarget::Error naming `key_path`.<field> for a value out of range.
  void validate(const std::string& key_path = "correspond.belief") const;
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
                            const Eigen::VectorXd& negative, const Eigen::VectorXd& lower,
                            const Eigen::VectorXd& upper, const BeliefSearchOptions& options);

// One decided comparison: the face of `positive` was judged nearer than that of `negative`.
// `metric` is G (C x C). A pair whose faces do not differ teaches nothing and leaves the belief
// as it was. Throws retarget::Error for sizes that differ.
void observe(Belief& belief, const Eigen::MatrixXd& metric, const Eigen::VectorXd& positive,
             const Eigen::VectorXd& negative, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
             const BeliefSearchOptions& options);

// The pair with the most expected information (above), each inside [lower, upper]; the two
// always differ when every range is not empty.
std::array<Eigen::VectorXd, 2> most_informative_pair(const Belief& belief, const Eigen::MatrixXd& metric,
                                                     const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                                                     const BeliefSearchOptions& options);

// The belief restricted to the box [lower, upper] (a Gaussian matching the moments of the
// belief truncated to the box, by expectation propagation over the 2C bounds, `sweeps` sweeps).
Belief truncated_belief(const Belief& belief, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                        int sweeps = 8);

// The belief's most likely weights inside the box: argmin over [lower, upper] of
// (c - mean)' Sigma^-1 (c - mean) (on a bound where the belief leans past it, correlations kept).
Eigen::VectorXd box_mode(const Belief& belief, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper);

// The truncated belief's mean (clamped, against rounding): the rig weights it bets on.
Eigen::VectorXd belief_estimate(const Belief& belief, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper);

}  // namespace retarget
