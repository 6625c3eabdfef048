#include "annotate/simulated_annotator.h"

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <string>
#include <vector>

#include "annotate_test_support.h"
#include "core/error.h"

namespace retarget {

using test::make_test_group;
using test::scratch_dir;
using test::TestGroup;

namespace {

std::vector<TestGroup> make_groups(int count, int candidates) {
  std::vector<TestGroup> groups;
  for (int g = 0; g < count; ++g)
    groups.push_back(make_test_group(fmt::format("expression {}", g), candidates, 100 * g));
  return groups;
}

void add_all(AnnotationStore& store, const std::vector<TestGroup>& groups) {
  for (const TestGroup& g : groups) store.create_group(g.label, g.samples, g.distances, 17);
}

}  // namespace

TEST_CASE("with noise 0 the simulated annotator finds the true best of every group", "[simulated]") {
  const int candidates = GENERATE(16, 5, 11);
  AnnotationStore store =
      AnnotationStore::open((scratch_dir(fmt::format("sim_best_{}", candidates)) / "a.db").string());
  const std::vector<TestGroup> groups = make_groups(4, candidates);
  add_all(store, groups);
  const SimulationCounts counts = run_simulated_annotation(store, test::scores_of(groups));
  CHECK(counts.finished);
  CHECK(counts.answers == 4 * (candidates - 1));
  CHECK(counts.decided == counts.answers);
  CHECK(counts.draws == 0);
  const StoreProgress p = store.progress();
  for (size_t i = 0; i < groups.size(); ++i) CHECK(*p.groups[i].champion == groups[i].best());
  // Every triplet, direct or derived, agrees with the scores.
  for (const Triplet& t : store.triplets()) {
    const TestGroup& g = groups[static_cast<size_t>(t.group - 1)];
    CHECK(g.score_of(t.positive) < g.score_of(t.negative));
  }
}

TEST_CASE("draws and noise: several simulated annotators still finish every group", "[simulated]") {
  AnnotationStore store = AnnotationStore::open((scratch_dir("sim_draws") / "a.db").string());
  const std::vector<TestGroup> groups = make_groups(6, 16);
  add_all(store, groups);
  SimulatedAnnotatorOptions options;
  options.noise = 5;
  options.draw_rate = 0.3;
  options.annotators = 3;
  options.seed = 4;
  const SimulationCounts counts = run_simulated_annotation(store, test::scores_of(groups), options);
  CHECK(counts.finished);
  CHECK(counts.decided + counts.tie_breaks == 6 * 15);
  CHECK(counts.draws > 0);
  CHECK(counts.answers == counts.decided + counts.draws);
  const StoreProgress p = store.progress();
  CHECK(p.annotators.size() == 3);
  int tie_breaks = 0;
  for (const GroupProgress& g : p.groups) tie_breaks += g.tie_breaks;
  CHECK(tie_breaks == counts.tie_breaks);
}

TEST_CASE("one simulated annotator who always draws: every comparison goes to the tie-break", "[simulated]") {
  AnnotationStore store = AnnotationStore::open((scratch_dir("sim_all_draws") / "a.db").string());
  const std::vector<TestGroup> groups = make_groups(1, 16);
  add_all(store, groups);
  SimulatedAnnotatorOptions options;
  options.draw_rate = 1;
  const SimulationCounts counts = run_simulated_annotation(store, test::scores_of(groups), options);
  CHECK(counts.finished);
  CHECK(counts.tie_breaks == 15);
  CHECK(counts.draws == 30);  // each comparison: a draw, back once, a second draw
  // The distances equal the scores here, so the tie-break finds the best too.
  CHECK(*store.progress().groups[0].champion == groups[0].best());
  for (const Triplet& t : store.triplets()) CHECK(t.tie_break);
}

TEST_CASE("the same seed gives the same answers", "[simulated]") {
  std::vector<std::vector<Triplet>> runs;
  for (int run = 0; run < 2; ++run) {
    AnnotationStore store = AnnotationStore::open((scratch_dir(fmt::format("sim_seed_{}", run)) / "a.db").string());
    const std::vector<TestGroup> groups = make_groups(3, 16);
    add_all(store, groups);
    SimulatedAnnotatorOptions options;
    options.noise = 20;
    options.draw_rate = 0.2;
    options.seed = 8;
    run_simulated_annotation(store, test::scores_of(groups), options);
    runs.push_back(store.triplets());
  }
  REQUIRE(runs[0].size() == runs[1].size());
  for (size_t i = 0; i < runs[0].size(); ++i) {
    CHECK(runs[0][i].positive == runs[1][i].positive);
    CHECK(runs[0][i].negative == runs[1][i].negative);
    CHECK(runs[0][i].tie_break == runs[1][i].tie_break);
  }
}

TEST_CASE("missing scores and bad options are reported before anything is answered", "[simulated]") {
  AnnotationStore store = AnnotationStore::open((scratch_dir("sim_errors") / "a.db").string());
  const std::vector<TestGroup> groups = make_groups(2, 4);
  add_all(store, groups);
  CandidateScores scores = test::scores_of(groups);
  scores["expression 1"].erase(101);  // group 1 holds samples 100..103
  CHECK_THROWS_WITH(run_simulated_annotation(store, scores),
                    Catch::Contains("group 'expression 1': no score for candidate sample 101"));
  scores.erase("expression 1");
  CHECK_THROWS_WITH(run_simulated_annotation(store, scores), Catch::Contains("no scores for group 'expression 1'"));
  CHECK(store.decisions().empty());

  SimulatedAnnotatorOptions options;
  options.draw_rate = 1.5;
  CHECK_THROWS_WITH(options.validate(),
                    Catch::Contains("simulated_annotator.draw_rate: expected a probability in [0, 1]"));
  options = {};
  options.noise = -1;
  CHECK_THROWS_WITH(options.validate(), Catch::Contains("simulated_annotator.noise"));
  options = {};
  options.annotators = 0;
  CHECK_THROWS_WITH(options.validate(), Catch::Contains("simulated_annotator.annotators: expected at least 1"));

  SimulatedAnnotator judge(test::scores_of(groups), {});
  Assignment a;
  a.label = "unknown";
  CHECK_THROWS_WITH(judge.judge(a), Catch::Contains("no scores for group 'unknown'"));
}

}  // namespace retarget

namespace retarget {

TEST_CASE("people-like judgement: draws when alike, lapses, Weber noise and fatigue", "[simulated]") {
  const std::vector<TestGroup> groups = make_groups(1, 2);
  const CandidateScores scores = test::scores_of(groups);
  const std::string& label = groups[0].label;
  Assignment a;
  a.label = label;
  a.left = groups[0].samples[0];
  a.right = groups[0].samples[1];
  const double gap = std::abs(groups[0].score_of(a.left) - groups[0].score_of(a.right));
  const Answer right_answer = groups[0].score_of(a.left) < groups[0].score_of(a.right) ? Answer::left : Answer::right;
  const auto tally = [&](const SimulatedAnnotatorOptions& o, int n) {
    SimulatedAnnotator judge(scores, o);
    std::map<Answer, int> counts;
    for (int i = 0; i < n; ++i) ++counts[judge.judge(a)];
    return counts;
  };
  SimulatedAnnotatorOptions o;
  CHECK(tally(o, 50)[right_answer] == 50);  // no noise: always right
  o.draw_margin = gap * 1.01;
  CHECK(tally(o, 50)[Answer::draw] == 50);  // the faces differ by less than the margin
  o = SimulatedAnnotatorOptions{};
  o.lapse_rate = 1;
  const auto lapses = tally(o, 400);
  CHECK(lapses.at(Answer::left) > 150);  // a coin: about half each way
  CHECK(lapses.at(Answer::right) > 150);
  // Noise proportional to the scores: wrong now and then, more so when tired.
  o = SimulatedAnnotatorOptions{};
  o.weber = 2;
  const int fresh_wrong = 2000 - tally(o, 2000)[right_answer];
  o.fatigue = 10000;  // ten times the noise after one answer, more later
  const int tired_wrong = 2000 - tally(o, 2000)[right_answer];
  CHECK(fresh_wrong > 0);
  CHECK(tired_wrong > fresh_wrong);
  o.weber = -1;
  CHECK_THROWS_WITH(tally(o, 1), Catch::Contains("weber"));
}

TEST_CASE("annotators with their own scores, and a budget of answers", "[simulated]") {
  AnnotationStore store = AnnotationStore::open((scratch_dir("sim_own_scores") / "a.db").string());
  const std::vector<TestGroup> groups = make_groups(4, 16);
  add_all(store, groups);
  SimulatedAnnotatorOptions options;
  options.annotators = 2;
  // Annotator 2 sees every score reversed; annotator 1 sees the truth.
  CandidateScores reversed = test::scores_of(groups);
  for (auto& [label, samples] : reversed)
    for (auto& [sample, score] : samples) score = -score;
  CHECK_THROWS_WITH(run_simulated_annotation(store, std::vector<CandidateScores>{reversed}, options),
                    Catch::Contains("1 score tables for 2 annotators"));
  const SimulationCounts some =
      run_simulated_annotation(store, std::vector<CandidateScores>{test::scores_of(groups), reversed}, options, 20);
  CHECK(some.answers == 20);
  CHECK_FALSE(some.finished);
  CHECK(store.progress().done() == 20);
  // The two readings disagree: some triplets say the opposite of the truth.
  int against = 0;
  for (const Triplet& t : store.triplets()) {
    const TestGroup& g = groups[static_cast<size_t>(t.group - 1)];
    against += g.score_of(t.positive) > g.score_of(t.negative);
  }
  CHECK(against > 0);
  // The rest of the budget-free run finishes every tournament.
  const SimulationCounts rest =
      run_simulated_annotation(store, std::vector<CandidateScores>{test::scores_of(groups), reversed}, options);
  CHECK(rest.finished);
  CHECK(some.answers + rest.answers == 4 * 15);
}

}  // namespace retarget
