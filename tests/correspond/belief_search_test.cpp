#include "correspond/belief_search.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "core/error.h"
#include "core/random.h"
#include "correspond/map_belief.h"

using Catch::Contains;
using namespace retarget;

namespace {

constexpr int kControllers = 11;  // as many as the shared rabbit's rig

// A face metric G = B'B from a random 60 x 11 "rig" whose controllers move the face unequally.
Eigen::MatrixXd random_metric(uint64_t seed) {
  Random random(seed);
  Eigen::MatrixXd b(60, kControllers);
  for (Eigen::Index j = 0; j < b.cols(); ++j) {
    const double strength = 0.3 + random.unit();
    for (Eigen::Index i = 0; i < b.rows(); ++i) b(i, j) = strength * random.normal();
  }
  Eigen::MatrixXd g = b.transpose() * b;
  return g / g.diagonal().mean();
}

double face_distance(const Eigen::MatrixXd& g, const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return std::sqrt((a - b).dot(g * (a - b)));
}

// An expression as an annotator means it: 3 controllers of 11 active; the start a table reads
// into it has one of them wrong and one controller the truth leaves alone.
struct Case {
  Eigen::VectorXd truth, start;
};

Case random_case(Random& random) {
  Case c{Eigen::VectorXd::Zero(kControllers), Eigen::VectorXd::Zero(kControllers)};
  std::vector<int64_t> order = random.permutation(kControllers);
  for (int i = 0; i < 3; ++i) c.truth(order[static_cast<size_t>(i)]) = random.uniform(0.3, 1.0);
  c.start = c.truth;
  c.start(order[0]) = 0;
  c.start(order[3]) = random.uniform(0.5, 1.0);
  return c;
}

// Judges like a person: the candidate whose face is nearer, with relative noise `weber` on each
// distance and the annotator's own reading of the truth (`reading` of each range).
struct Judge {
  double weber = 0, reading = 0;
  bool prefers_first(Random& random, const Eigen::MatrixXd& g, const Eigen::VectorXd& truth, const Eigen::VectorXd& a,
                     const Eigen::VectorXd& b) const {
    Eigen::VectorXd meant = truth;
    for (Eigen::Index i = 0; i < meant.size(); ++i) meant(i) += reading * random.normal();
    const double da = face_distance(g, a, meant), db = face_distance(g, b, meant);
    return da * (1 + weber * random.normal()) < db * (1 + weber * random.normal());
  }
};

// The mean face distance to the truth of the start and of the belief after `comparisons`
// informative pairs per expression, over `cases` expressions.
std::pair<double, double> search(const Judge& judge, int comparisons, int cases, uint64_t seed) {
  const Eigen::MatrixXd g = random_metric(seed);
  const Eigen::VectorXd lower = Eigen::VectorXd::Zero(kControllers), upper = Eigen::VectorXd::Ones(kControllers);
  const BeliefSearchOptions options;
  Random random(seed + 1);
  double before = 0, after = 0;
  for (int k = 0; k < cases; ++k) {
    const Case c = random_case(random);
    Belief belief = prior_belief(c.start, lower, upper, options);
    for (int t = 0; t < comparisons; ++t) {
      const auto [a, b] = most_informative_pair(belief, g, lower, upper, options);
      if (judge.prefers_first(random, g, c.truth, a, b))
        observe(belief, g, a, b, lower, upper, options);
      else
        observe(belief, g, b, a, lower, upper, options);
    }
    before += face_distance(g, c.start, c.truth) / cases;
    after += face_distance(g, belief_estimate(belief, lower, upper), c.truth) / cases;
  }
  return {before, after};
}

}  // namespace

TEST_CASE("belief search: 42 comparisons (2,000 over 47 expressions) find a wrong start's truth", "[belief]") {
  SECTION("an annotator who judges exactly") {
    const auto [before, after] = search(Judge{}, 42, 20, 11);
    INFO("face distance to the truth: start " << before << ", after " << after);
    CHECK(after < 0.45 * before);
  }
  SECTION("people-like annotators: relative noise and their own readings") {
    const auto [before, after] = search(Judge{0.2, 0.08}, 42, 20, 12);
    INFO("face distance to the truth: start " << before << ", after " << after);
    CHECK(after < 0.55 * before);
  }
  SECTION("more comparisons teach more") {
    const Judge people{0.2, 0.08};
    CHECK(search(people, 42, 20, 13).second < search(people, 8, 20, 13).second);
  }
}

TEST_CASE("belief search: an answer moves the belief towards the chosen face and narrows it there", "[belief]") {
  const Eigen::MatrixXd g = random_metric(3);
  const Eigen::VectorXd lower = Eigen::VectorXd::Zero(kControllers), upper = Eigen::VectorXd::Ones(kControllers);
  BeliefSearchOptions options;
  options.reading_sd = 0.08;  // one careful annotator's spread: how much one answer narrows depends on it
  Belief belief = prior_belief(Eigen::VectorXd::Constant(kControllers, 0.5), lower, upper, options);
  const auto [a, b] = most_informative_pair(belief, g, lower, upper, options);
  // The pair lies inside the ranges, differs, and straddles the (unclamped) mean.
  CHECK((a.array() >= 0).all());
  CHECK((b.array() <= 1).all());
  CHECK(face_distance(g, a, b) > 0.1);
  CHECK(((a + b) / 2 - belief.mean).norm() < 1e-9);
  const Eigen::VectorXd n = g * (a - b);
  const double spread_before = n.dot(belief.covariance * n);
  const double lean_before = face_distance(g, belief.mean, b) - face_distance(g, belief.mean, a);
  observe(belief, g, a, b, lower, upper, options);
  CHECK(face_distance(g, belief.mean, b) - face_distance(g, belief.mean, a) > lean_before + 0.05);
  CHECK(n.dot(belief.covariance * n) < 0.7 * spread_before);
  CHECK(belief.covariance.isApprox(belief.covariance.transpose()));
  // A pair whose faces are the same teaches nothing.
  const Belief kept = belief;
  observe(belief, g, a, a, lower, upper, options);
  CHECK(belief.mean == kept.mean);
}

TEST_CASE("belief search: the pair stays inside the ranges when the belief sits on a bound", "[belief]") {
  const Eigen::MatrixXd g = random_metric(4);
  const Eigen::VectorXd lower = Eigen::VectorXd::Zero(kControllers), upper = Eigen::VectorXd::Ones(kControllers);
  Belief belief = prior_belief(Eigen::VectorXd::Zero(kControllers), lower, upper, BeliefSearchOptions{});
  belief.mean(0) = -0.7;  // a mean pushed past the range by answers
  const auto [a, b] = most_informative_pair(belief, g, lower, upper, BeliefSearchOptions{});
  CHECK((a.array() >= 0).all());
  CHECK((b.array() >= 0).all());
  CHECK((a - b).norm() > 0.05);
  CHECK(belief_estimate(belief, lower, upper)(0) == 0.0);
}

TEST_CASE("belief search: options and shapes are checked", "[belief]") {
  BeliefSearchOptions o;
  o.lapse = 0.5;
  CHECK_THROWS_WITH(o.validate(), Contains("correspond.belief.lapse") && Contains("[0, 0.5)"));
  o = {};
  o.prior_sd = 0;
  CHECK_THROWS_WITH(o.validate("rounds.belief"), Contains("rounds.belief.prior_sd"));
  const Eigen::VectorXd lower = Eigen::VectorXd::Zero(3), upper = Eigen::VectorXd::Ones(3);
  CHECK_THROWS_WITH(prior_belief(Eigen::VectorXd::Zero(4), lower, upper, BeliefSearchOptions{}),
                    Contains("4 controllers"));
  Eigen::VectorXd empty_range = upper;
  empty_range(1) = 0;
  CHECK_THROWS_WITH(prior_belief(Eigen::VectorXd::Zero(3), lower, empty_range, BeliefSearchOptions{}),
                    Contains("controller 1 has an empty range"));
}

TEST_CASE("map belief: a comparison teaches every expression that shares its shapes, and no other", "[belief]") {
  // Two controllers, three shapes; the prior maps shape 0 to controller 0 at 0.2 (truth: 1).
  ControllerMap prior;
  prior.controllers = {"c0", "c1"};
  prior.shapes = {"s0", "s1", "s2"};
  prior.matrix = Eigen::MatrixXd::Zero(2, 3);
  prior.matrix(0, 0) = 0.2;
  const Eigen::VectorXd lower = Eigen::VectorXd::Zero(2), upper = Eigen::VectorXd::Ones(2);
  const Eigen::MatrixXd g = Eigen::MatrixXd::Identity(2, 2);
  MapBelief belief(prior, lower, upper, BeliefSearchOptions{});
  const Eigen::VectorXd only_s0 = belief.recipe_vector({{"s0", 1.0}});
  const Eigen::VectorXd s0_and_s1 = belief.recipe_vector({{"s0", 0.5}, {"s1", 1.0}, {"unknown", 1.0}});
  const Eigen::VectorXd only_s2 = belief.recipe_vector({{"s2", 1.0}});
  CHECK(belief.expression(s0_and_s1).mean(0) == Approx(0.1));
  // The truth's face (c0 = 1) judged nearer than the prior's.
  Eigen::VectorXd truth(2), start(2);
  truth << 1, 0;
  start << 0.2, 0;
  for (int i = 0; i < 5; ++i) belief.observe(only_s0, g, truth, start);
  CHECK(belief.observed() == 5);
  CHECK(belief.expression(only_s0).mean(0) > 0.6);
  CHECK(belief.expression(s0_and_s1).mean(0) > 0.3);  // shares s0
  CHECK(belief.expression(only_s2).mean.norm() == Approx(0).margin(1e-12));
  CHECK(belief.expression(only_s2).covariance(0, 0) == Approx(0.25));  // untouched: prior_sd 0.5 of the range
  const ControllerMap mean = belief.likely_map();
  CHECK(mean.pairs == 5);
  // The map's reading: the answers outweigh the pull on (c0, s0), which moves most of the way
  // (less than the Gaussian's mean: pulled towards the prior's 0.2); untaught entries stay.
  CHECK(mean.matrix(0, 0) > 0.55);
  CHECK(mean.matrix(0, 0) <= belief.expression(only_s0).mean(0));
  CHECK(mean.matrix(1, 2) == 0.0);
  CHECK(mean.matrix(0, 2) == 0.0);
  // The next pair for s0 lies in the ranges and differs.
  const auto [a, b] = belief.next_pair(only_s0, g);
  CHECK((a - b).norm() > 0.01);
  CHECK_THROWS_WITH(belief.expression(Eigen::VectorXd::Zero(4)), Contains("a recipe of 4 weights for a map of 3"));
}

TEST_CASE("map belief: with the table's zeros surer than its shares, a pucker's pair asks about the pucker",
          "[belief]") {
  // A jaw that moves the face five times as much as the pucker; the prior reads each controller
  // as its own shape, the pucker at half its weight (the truth, say, at 1).
  ControllerMap prior;
  prior.controllers = {"jaw", "pucker"};
  prior.shapes = {"jawOpen", "mouthPucker"};
  prior.matrix = Eigen::MatrixXd::Zero(2, 2);
  prior.matrix(0, 0) = 1;
  prior.matrix(1, 1) = 0.5;
  const Eigen::VectorXd lower = Eigen::VectorXd::Zero(2), upper = Eigen::VectorXd::Ones(2);
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(2, 2);
  g(0, 0) = 25;
  g(1, 1) = 1;
  const auto belief_with = [&](double off_table) {
    BeliefSearchOptions options;
    options.off_table = off_table;
    return MapBelief(prior, lower, upper, options);
  };
  const auto pair_gap = [&](double off_table) {
    const MapBelief belief = belief_with(off_table);
    const auto [a, b] = belief.next_pair(belief.recipe_vector({{"mouthPucker", 1.0}}), g);
    return (a - b).cwiseAbs().eval();
  };
  // The default, every zero as unsure as a share: the pair asks whether the pucker opens the jaw.
  REQUIRE(BeliefSearchOptions{}.off_table == 1.0);
  const Eigen::VectorXd unsure = pair_gap(1.0), surer = pair_gap(0.3);
  INFO("pair gaps (jaw, pucker): every entry alike " << unsure.transpose() << ", the zeros surer "
                                                     << surer.transpose());
  CHECK(unsure(0) > unsure(1));
  // The zeros surer: it asks how far the pucker goes.
  CHECK(surer(1) > 0.2);
  CHECK(surer(1) > surer(0));
  // Only the zeros of a row the prior reads narrow; its shares and an empty row's entries keep prior_sd.
  const MapBelief narrow = belief_with(0.3);
  const Eigen::VectorXd pucker_recipe = narrow.recipe_vector({{"mouthPucker", 1.0}});
  CHECK(narrow.expression(pucker_recipe).covariance(0, 0) == Approx(0.25 * 0.09));
  CHECK(narrow.expression(pucker_recipe).covariance(1, 1) == Approx(0.25));
  BeliefSearchOptions bad;
  bad.off_table = 0;
  CHECK_THROWS_WITH(bad.validate(), Contains("correspond.belief.off_table"));
  bad.off_table = 1.5;
  CHECK_THROWS_WITH(bad.validate(), Contains("expected a fraction in (0, 1]"));
}

// Answers of a noisy reader about two controllers and three shapes, each pair a random one in
// the ranges; the same answers in two orders.
struct OrderedAnswers {
  std::vector<Eigen::VectorXd> recipes, positive, negative;
};
OrderedAnswers noisy_answers(const MapBelief& belief, int count) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Eigen::MatrixXd truth(2, 3);
  truth << 1, 0, 0.3, 0, 0.8, 0.5;
  const std::vector<Eigen::VectorXd> recipes = {belief.recipe_vector({{"s0", 1.0}}),
                                                belief.recipe_vector({{"s1", 1.0}, {"s2", 0.5}}),
                                                belief.recipe_vector({{"s0", 0.6}, {"s2", 1.0}})};
  OrderedAnswers a;
  for (int i = 0; i < count; ++i) {
    const Eigen::VectorXd& r = recipes[static_cast<size_t>(i) % recipes.size()];
    const Eigen::VectorXd target = truth * r;
    Eigen::VectorXd x(2), y(2);
    x << unit(random), unit(random);
    y << unit(random), unit(random);
    // The reader's distance, with 10% of the answers flipped.
    const bool x_nearer = ((x - target).norm() < (y - target).norm()) != (unit(random) < 0.1);
    a.recipes.push_back(r);
    a.positive.push_back(x_nearer ? x : y);
    a.negative.push_back(x_nearer ? y : x);
  }
  return a;
}

// Two controllers of range [0, 1] and three shapes, the prior all zeros.
MapBelief zero_belief(const BeliefSearchOptions& options) {
  ControllerMap prior;
  prior.controllers = {"c0", "c1"};
  prior.shapes = {"s0", "s1", "s2"};
  prior.matrix = Eigen::MatrixXd::Zero(2, 3);
  return MapBelief(prior, Eigen::VectorXd::Zero(2), Eigen::VectorXd::Ones(2), options);
}

// The map `belief` bets on after `answers` (metric: identity), in their order or reversed, refined
// `passes` times.
Eigen::MatrixXd map_after(MapBelief belief, const OrderedAnswers& answers, bool reversed, int passes) {
  const Eigen::MatrixXd g = Eigen::MatrixXd::Identity(2, 2);
  for (size_t k = 0; k < answers.recipes.size(); ++k) {
    const size_t i = reversed ? answers.recipes.size() - 1 - k : k;
    belief.observe(answers.recipes[i], g, answers.positive[i], answers.negative[i]);
  }
  belief.refine(passes);
  return belief.likely_map().matrix;
}

TEST_CASE("map belief: expectation propagation reads the same answers to the same map in any order", "[belief]") {
  const MapBelief empty = zero_belief(BeliefSearchOptions{});
  const OrderedAnswers answers = noisy_answers(empty, 120);
  const auto read = [&](bool reversed, int passes) { return map_after(empty, answers, reversed, passes); };
  const double one_pass = (read(false, 0) - read(true, 0)).cwiseAbs().maxCoeff();
  const double refined = (read(false, 6) - read(true, 6)).cwiseAbs().maxCoeff();
  INFO("the two orders' maps differ by " << one_pass << " in one pass, " << refined << " refined");
  CHECK(one_pass > 0.01);  // the one-pass belief depends on the order
  CHECK(refined < 0.2 * one_pass);
  // Refining keeps what was learnt: the entry the answers teach most moves off the prior's 0.
  CHECK(read(false, 6)(0, 0) > 0.5);
  CHECK(read(false, 6).allFinite());
}

TEST_CASE("map belief: the rig head's reading of the answers does not depend on their order", "[belief]") {
  // BeliefSearchOptions::map_reading(), as `retarget rig-map fit --belief` reads the rounds.
  const BeliefSearchOptions reading = BeliefSearchOptions::map_reading();
  REQUIRE_NOTHROW(reading.validate());
  const OrderedAnswers answers = noisy_answers(zero_belief(reading), 120);
  const auto read = [&](bool reversed, const BeliefSearchOptions& options) {
    return map_after(zero_belief(options), answers, reversed, options.refine_passes);
  };
  const double search = (read(false, BeliefSearchOptions{}) - read(true, BeliefSearchOptions{})).cwiseAbs().maxCoeff();
  const double rig_head = (read(false, reading) - read(true, reading)).cwiseAbs().maxCoeff();
  INFO("the two orders' maps differ by " << search << " as the search reads them, " << rig_head
                                         << " as the rig head does");
  CHECK(rig_head < 0.25 * search);
  CHECK(read(false, reading)(0, 0) > 0.5);  // what the answers teach most is still learnt
}

// One controller of range [0, 2] and one shape, prior 0.2: a map entry annotators read their own way.
MapBelief one_entry_belief(const BeliefSearchOptions& options) {
  ControllerMap prior;
  prior.controllers = {"c0"};
  prior.shapes = {"s0"};
  prior.matrix = Eigen::MatrixXd::Constant(1, 1, 0.2);
  return MapBelief(prior, Eigen::VectorXd::Zero(1), Eigen::VectorXd::Constant(1, 2.0), options);
}

// One comparison of two random faces on one_entry_belief's entry, answered by `who` (named in the
// answer when `named`), who reads the shape as the controller at `reading`.
void answer_as(MapBelief& belief, std::mt19937& random, const std::string& who, double reading, bool named = true) {
  std::uniform_real_distribution<double> unit(0.0, 2.0);
  Eigen::VectorXd x(1), y(1);
  x << unit(random);
  y << unit(random);
  const bool x_nearer = std::abs(x(0) - reading) < std::abs(y(0) - reading);
  belief.observe(belief.recipe_vector({{"s0", 1.0}}), Eigen::MatrixXd::Identity(1, 1), x_nearer ? x : y,
                 x_nearer ? y : x, named ? who : "");
}

TEST_CASE("map belief: one annotator's many answers teach the shared map no more than one reading", "[belief]") {
  // One entry (one_entry_belief). Annotator "a" reads the shape as the controller at 1.2 and
  // answers 200 comparisons; "b" and "c" read it as 0.2 and answer 10 each.
  const auto read = [&](double annotator_sd, bool names) {
    BeliefSearchOptions options = BeliefSearchOptions::map_reading();
    options.sparsity = 0;  // the Gaussian's own mode
    options.annotator_sd = annotator_sd;
    options.jackknife_z = 0;  // the shared map alone
    options.jackknife_if_it_predicts = false;
    MapBelief belief = one_entry_belief(options);
    std::mt19937 random(5);
    for (int i = 0; i < 200; ++i) answer_as(belief, random, "a", 1.2, names);
    for (int i = 0; i < 10; ++i) answer_as(belief, random, "b", 0.2, names);
    for (int i = 0; i < 10; ++i) answer_as(belief, random, "c", 0.2, names);
    belief.refine(options.refine_passes);
    return belief.likely_map().matrix(0, 0);
  };
  const double pooled = read(0.0, true), shared = read(0.25, true), unnamed = read(0.25, false);
  INFO("pooled " << pooled << ", shared " << shared << ", answers without names " << unnamed);
  CHECK(pooled > 1.0);                            // 200 answers against 20 carry the pooled map
  CHECK(shared < 0.7);                            // one reader against two: the shared map stays nearer theirs
  CHECK(shared > 0.3);                            // but it does listen to "a"
  CHECK(unnamed == Approx(pooled).margin(0.02));  // no names: read as before
  REQUIRE_THROWS_WITH(
      [] {
        BeliefSearchOptions o;
        o.annotator_sd = -1;
        o.validate();
      }(),
      Contains("annotator_sd"));
}

// one_entry_belief's entry as `options` read it after six (or any number of) annotators answer
// 60 comparisons each (drawn from `seed`), annotator a reading the shape as the controller at
// readings[a]; without a sparse pull, so the figures are the Gaussian's.
double read_by_annotators(const std::vector<double>& readings, BeliefSearchOptions options, uint32_t seed = 13) {
  options.sparsity = 0;
  MapBelief belief = one_entry_belief(options);
  std::mt19937 random(seed);
  for (int i = 0; i < 60; ++i)
    for (size_t a = 0; a < readings.size(); ++a) answer_as(belief, random, "a" + std::to_string(a), readings[a]);
  belief.refine(options.refine_passes);
  return belief.likely_map().matrix(0, 0);
}

TEST_CASE("map belief: left one out, what one annotator alone says moves nothing; what several say still moves",
          "[belief]") {
  // One entry (one_entry_belief); each annotator answers 60 comparisons with their own reading.
  const auto read = [&](const std::vector<double>& readings, bool leave_one_out, double annotator_sd) {
    BeliefSearchOptions options = BeliefSearchOptions::map_reading();
    options.annotator_sd = annotator_sd;
    options.leave_one_out = leave_one_out;
    options.jackknife_z = 0;  // pooled or left one out, nothing else
    options.jackknife_if_it_predicts = false;
    return read_by_annotators(readings, options, 9);
  };
  for (const double annotator_sd : {0.0, 0.15}) {
    const double alone = read({1.2, 0.2, 0.2}, false, annotator_sd),
                 alone_left = read({1.2, 0.2, 0.2}, true, annotator_sd);
    const double agreed = read({1.2, 1.2, 1.2}, false, annotator_sd),
                 agreed_left = read({1.2, 1.2, 1.2}, true, annotator_sd);
    INFO("annotator sd " << annotator_sd << ": one of three reads 1.2: " << alone << ", left one out " << alone_left
                         << "; all three: " << agreed << ", left one out " << agreed_left);
    CHECK(alone > 0.28);                            // read as they come, the one reader moves the map
    CHECK(alone_left == Approx(0.2).margin(0.03));  // left one out, the map stays at the prior's
    CHECK(agreed_left > 1.1);                       // three who agree still move it all the way
    CHECK(agreed_left == Approx(agreed).margin(0.1));
  }
}

// The rig head's reading with the jackknife at strength z itself (0: pooled), not its choice.
double read_at_strength(const std::vector<double>& readings, double z) {
  BeliefSearchOptions options = BeliefSearchOptions::map_reading();
  options.jackknife_z = z;
  options.jackknife_if_it_predicts = false;
  return read_by_annotators(readings, options);
}

TEST_CASE("map belief: jackknifed, a move a few annotators make shrinks to the prior; one they all make stays",
          "[belief]") {
  // The prior at 0.2; the jackknife itself (z = 2), not the rig head's choice of it.
  const auto read = read_at_strength;
  const std::vector<double> two_of_six{1.2, 1.2, 0.2, 0.2, 0.2, 0.2}, all_six{1.1, 1.3, 1.2, 1.15, 1.25, 1.2};
  const double few = read(two_of_six, 0), few_jack = read(two_of_six, 2);
  const double all = read(all_six, 0), all_jack = read(all_six, 2);
  INFO("two of six read 1.2: " << few << ", jackknifed " << few_jack << "; all six: " << all << ", jackknifed "
                               << all_jack);
  CHECK(few > 0.4);                            // pooled, two readers move the map a third of the way
  CHECK(few_jack < 0.2 + 0.25 * (few - 0.2));  // jackknifed, most of that move is gone
  CHECK(few_jack >= 0.2 - 1e-9);               // shrunk towards the prior, never past it
  CHECK(all > 1.0);
  CHECK(all_jack > 0.2 + 0.9 * (all - 0.2));  // six who agree keep nearly all of it
  REQUIRE_THROWS_WITH(
      [] {
        BeliefSearchOptions o;
        o.jackknife_z = -1;
        o.validate();
      }(),
      Contains("jackknife_z"));
}

TEST_CASE("map belief: the rig head's reading jackknifes a minority's move away and keeps a move all make",
          "[belief]") {
  // The prior at 0.2; the rig head's default reading (jackknifed only where that predicts
  // held-out annotators) against the pooled map.
  const auto read = [](const std::vector<double>& readings, bool choose) {
    BeliefSearchOptions options = BeliefSearchOptions::map_reading();
    if (!choose) options.jackknife_z = 0, options.jackknife_if_it_predicts = false;
    return read_by_annotators(readings, options);
  };
  // Two of six misread a table that is right; six read a wrong one their own way, all above it.
  const std::vector<double> two_of_six{1.2, 1.2, 0.2, 0.2, 0.2, 0.2}, spread{0.6, 1.9, 0.8, 1.6, 1.0, 1.4};
  const double few = read(two_of_six, false), few_read = read(two_of_six, true);
  const double apart = read(spread, false), apart_read = read(spread, true);
  INFO("two of six: pooled " << few << ", the rig head's reading " << few_read << "; six apart: pooled " << apart
                             << ", the rig head's reading " << apart_read);
  CHECK(few > 0.4);
  CHECK(few_read < 0.2 + 0.25 * (few - 0.2));  // the jackknife, chosen: the minority's move is gone
  CHECK(apart > 1.0);
  CHECK(apart_read == Approx(apart).margin(1e-9));  // the pooled map, chosen: the move they share stays
  // At z = 0 the choice has nothing to choose: the pooled map, as `--belief-jackknife 0` asks.
  BeliefSearchOptions pooled = BeliefSearchOptions::map_reading();
  pooled.jackknife_z = 0;
  CHECK(read_by_annotators(two_of_six, pooled) == Approx(few).margin(1e-12));
}

TEST_CASE(
    "map belief: the rig head's reading also tries a stronger jackknife and keeps the one held-out people "
    "predict best",
    "[belief]") {
  // The prior at 0.2. Three of six misread a table that is right: jackknifed at z = 1 (the
  // reading's first strength) part of their move stays; at z = 2 none. Held out, each of the three
  // who read it right is predicted better by the table, so the reading that also tries z = 2
  // (the rig head's default) keeps the table. Six who read it each their own way, all above it,
  // keep the pooled map whatever is tried.
  const auto fixed = read_at_strength;
  const auto chosen = [](const std::vector<double>& readings, const std::vector<double>& alternatives) {
    BeliefSearchOptions options = BeliefSearchOptions::map_reading();
    options.jackknife_alternatives = alternatives;
    return read_by_annotators(readings, options);
  };
  REQUIRE(BeliefSearchOptions::map_reading().jackknife_alternatives == std::vector<double>{2});
  const std::vector<double> half{1.2, 1.2, 1.2, 0.2, 0.2, 0.2}, spread{0.6, 1.9, 0.8, 1.6, 1.0, 1.4};
  const double z1 = fixed(half, 1), z2 = fixed(half, 2);
  INFO("three of six read 1.2: z 1 " << z1 << ", z 2 " << z2 << "; chosen from z 1 " << chosen(half, {})
                                     << ", from z 1 and 2 " << chosen(half, {2}));
  REQUIRE(z1 > 0.3);                                    // at z = 1 part of the move stays
  REQUIRE(z2 == Approx(0.2).margin(0.01));              // at z = 2 it is gone
  CHECK(chosen(half, {}) == Approx(z1).margin(1e-9));   // z = 1 beats the pooled map...
  CHECK(chosen(half, {2}) == Approx(z2).margin(1e-9));  // ...and z = 2 beats z = 1
  const double pooled = fixed(spread, 0);
  CHECK(chosen(spread, {2, 3}) == Approx(pooled).margin(1e-9));
  CHECK(fixed(spread, 3) < pooled - 0.5);  // z = 3 was a real alternative there
  REQUIRE_THROWS_WITH(
      [] {
        BeliefSearchOptions o;
        o.jackknife_alternatives.push_back(2);
        o.jackknife_alternatives.push_back(-1);
        o.validate("rig_head.belief");
      }(),
      Contains("rig_head.belief.jackknife_alternatives"));
}

TEST_CASE("map belief: answers that only ever say 'more' leave the map inside the range", "[belief]") {
  // One controller at its top for shape 0: the truth's face (c0 = 1) always beats 0.8, so the
  // Gaussian's mean climbs past 1 and a blend with another shape would be read from a share
  // the rig cannot have. The map stays in the range; without a pull, on its top.
  ControllerMap prior;
  prior.controllers = {"c0"};
  prior.shapes = {"s0", "s1"};
  prior.matrix = Eigen::MatrixXd::Zero(1, 2);
  prior.matrix(0, 0) = 0.9;
  const Eigen::VectorXd lower = Eigen::VectorXd::Zero(1), upper = Eigen::VectorXd::Ones(1);
  BeliefSearchOptions plain;
  plain.sparsity = 0;
  MapBelief belief(prior, lower, upper, plain);
  const Eigen::VectorXd s0 = belief.recipe_vector({{"s0", 1.0}});
  for (int i = 0; i < 30; ++i)
    belief.observe(s0, Eigen::MatrixXd::Identity(1, 1), upper, Eigen::VectorXd::Constant(1, 0.8));
  REQUIRE(belief.expression(s0).mean(0) > 1.05);
  const ControllerMap map = belief.likely_map();
  CHECK(map.matrix(0, 0) == Approx(1.0));
  CHECK(map.matrix(0, 1) == Approx(0.0).margin(1e-12));
}

TEST_CASE("map belief: a controller that barely moves the face is reported as one no answer reached", "[belief]") {
  // c0 moves the face; c1 moves it 1,000 times less (a fox's snarl beside its jaw). Every pair
  // differs on both, as the truth's face against the prior's.
  ControllerMap prior;
  prior.controllers = {"c0", "c1"};
  prior.shapes = {"s0", "s1"};
  prior.matrix = Eigen::MatrixXd::Zero(2, 2);
  const Eigen::VectorXd lower = Eigen::VectorXd::Zero(2), upper = Eigen::VectorXd::Ones(2);
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(2, 2);
  g(0, 0) = 1.0;
  g(1, 1) = 1e-3;
  MapBelief belief(prior, lower, upper, BeliefSearchOptions{});
  CHECK(belief.unreached_controllers().empty());  // nothing observed yet
  const Eigen::VectorXd recipe = belief.recipe_vector({{"s0", 1.0}});
  Eigen::VectorXd truth(2), start(2);
  truth << 0.8, 0.8;
  start << 0.2, 0.2;
  for (int i = 0; i < 20; ++i) belief.observe(recipe, g, truth, start);
  CHECK(belief.unreached_controllers() == std::vector<std::string>{"c1"});
  // With c1 as visible as c0, both are reached.
  MapBelief visible(prior, lower, upper, BeliefSearchOptions{});
  for (int i = 0; i < 20; ++i) visible.observe(recipe, Eigen::MatrixXd::Identity(2, 2), truth, start);
  CHECK(visible.unreached_controllers().empty());
  CHECK_THROWS_WITH(belief.unreached_controllers(0.0), Contains("kept: expected (0, 1]"));
}
