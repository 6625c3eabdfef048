#include "correspond/annotation_project.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <vector>

#include "annotate/annotation_store.h"
#include "cli/cli.h"
#include "core/error.h"
#include "tiny_correspondence.h"

using namespace retarget;
using namespace retarget::test;
namespace fs = std::filesystem;

namespace {

// Correspondences of the tiny data: 4 groups of 8.
const std::string& correspondences() {
  static const std::string folder = [] {
    const auto& d = tiny_correspondence_data();
    CorrespondenceOptions o;
    o.group_size = 8;
    o.progress = nullptr;
    return build_correspondences(d.human, d.avatar, d.run,
                                 (process_scratch_dir("annotation_project_corr") / "c").string(), o)
        .folder;
  }();
  return folder;
}

GroundTruth truth_for(const Correspondences& c) {
  const auto& d = tiny_correspondence_data();
  return ground_truth_scores(c, load_dataset(d.human), load_dataset(d.avatar), load_controller_correspondence(d.table),
                             d.table);
}

// Runs `retarget ARGS...` in-process.
int run_cli(std::vector<std::string> args) {
  args.insert(args.begin(), "retarget");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  return cli::run(static_cast<int>(argv.size()), argv.data());
}

}  // namespace

TEST_CASE("annotation project: init and a noiseless simulation find the ground-truth best", "[annotation_project]") {
  const fs::path dir = scratch_dir("annotation_project_e2e");
  AnnotationProjectOptions o;
  o.seed = 3;
  const AnnotationProject project = init_annotation_project(correspondences(), (dir / "p").string(), o);
  CHECK(fs::exists(dir / "p" / "project.yaml"));
  const AnnotationProject loaded = load_annotation_project(project.folder);
  CHECK(loaded.seed == 3);
  CHECK(loaded.correspondences == fs::absolute(correspondences()).lexically_normal().string());

  const Correspondences c = load_correspondences(correspondences());
  AnnotationStore store = AnnotationStore::open(loaded.database());
  const std::vector<GroupInfo> groups = store.groups();
  REQUIRE(groups.size() == 4);
  // The groups come in the project's queue order, each with its own expression's group.
  const std::vector<int64_t> order = queue_order(3, 4);
  for (size_t i = 0; i < groups.size(); ++i) {
    const int64_t k = order[i];
    CHECK(groups[i].label == c.expressions[k]);
    REQUIRE(groups[i].candidates.size() == 8);
    for (int p = 0; p < 8; ++p) {
      CHECK(groups[i].candidates[p] == c.groups[k][p].item<int64_t>());
      CHECK(groups[i].distances[p] == Approx(c.distances[k][p].item<double>()));
    }
    CHECK(groups[i].seed == group_seed(3, k));
  }
  CHECK(group_seed(3, 0) != group_seed(3, 1));

  const GroundTruth truth = truth_for(c);
  // The A recipe (a: 1) maps to ctrl0 = 1 and nothing else.
  const std::map<std::string, std::vector<double>> expected = {{"A", {1, 0, 0, 0}}, {"AB", {0.5, 1, 0, 0}}};
  for (const auto& [label, weights] : expected)
    for (size_t j = 0; j < weights.size(); ++j)
      CHECK(truth.controller_weights.at(label)[j] == Approx(weights[j]).margin(1e-6));
  SimulatedAnnotatorOptions sim;
  sim.annotators = 2;
  const SimulationCounts counts = run_simulated_annotation(store, truth.scores, sim);
  CHECK(counts.finished);
  CHECK(counts.decided == 4 * 7);
  CHECK(counts.draws == 0);
  for (const GroupProgress& g : store.progress().groups) {
    INFO(g.label);
    REQUIRE(g.champion.has_value());
    const auto& scores = truth.scores.at(g.label);
    int64_t best = scores.begin()->first;
    for (const auto& [sample, score] : scores)
      if (score < scores.at(best)) best = sample;
    CHECK(*g.champion == best);
  }

  // Triplets through the project folder or the .db file.
  const std::vector<Triplet> direct = load_project_triplets(project.folder, false);
  CHECK(direct.size() == 4 * 7);
  const std::vector<Triplet> all = load_project_triplets(project.database(), true);
  CHECK(all.size() > direct.size());
  for (const Triplet& t : direct) {
    const auto& scores = truth.scores.at(t.anchor);
    CHECK(scores.at(t.positive) <= scores.at(t.negative));
  }
  CHECK_THROWS_WITH(load_project_triplets((dir / "nothing").string(), true),
                    Catch::Contains("nothing") && Catch::Contains("no such annotation project"));
  CHECK_THROWS_WITH(load_project_triplets(dir.string(), true), Catch::Contains("not an annotation project"));
}

TEST_CASE("annotation project: noisy annotators with draws still finish every group", "[annotation_project]") {
  const fs::path dir = scratch_dir("annotation_project_noisy");
  const AnnotationProject project = init_annotation_project(correspondences(), (dir / "p").string());
  AnnotationStore store = AnnotationStore::open(project.database());
  SimulatedAnnotatorOptions sim;
  sim.noise = 0.05;
  sim.draw_rate = 0.2;
  sim.annotators = 3;
  sim.seed = 5;
  const SimulationCounts counts =
      run_simulated_annotation(store, truth_for(load_correspondences(project.correspondences)).scores, sim);
  CHECK(counts.finished);
  CHECK(counts.draws > 0);
  CHECK(store.finished());
}

TEST_CASE("annotation project: each round's seed hands an expression to other people", "[annotation_project]") {
  // Three annotators take turns at the queue, as in every round of the pipeline. With one seed
  // for every round the same person would open each expression's bracket every time; each
  // round's own seed queues the groups in another order.
  const fs::path dir = scratch_dir("annotation_project_queue");
  const Correspondences c = load_correspondences(correspondences());
  std::map<std::string, std::set<std::string>> openers;  // expression -> who answered its first comparison
  for (uint64_t round = 1; round <= 6; ++round) {
    AnnotationProjectOptions o;
    o.seed = round;
    const AnnotationProject project =
        init_annotation_project(correspondences(), (dir / std::to_string(round)).string(), o);
    AnnotationStore store = AnnotationStore::open(project.database());
    SimulatedAnnotatorOptions sim;
    sim.annotators = 3;
    const SimulationCounts counts = run_simulated_annotation(store, truth_for(c).scores, sim);
    REQUIRE(counts.finished);
    std::map<int64_t, std::string> labels;
    for (const GroupInfo& g : store.groups()) labels[g.id] = g.label;
    for (const ComparisonRecord& r : store.comparisons())
      if (r.round == 1 && r.position == 0) openers[labels.at(r.group)].insert(r.assigned_to);
  }
  REQUIRE(openers.size() == c.expressions.size());
  for (const auto& [label, who] : openers) {
    INFO(label);
    CHECK(who.size() >= 2);
  }
  CHECK(queue_order(1, 10) != queue_order(2, 10));
  std::vector<int64_t> sorted = queue_order(4, 10);
  std::sort(sorted.begin(), sorted.end());
  for (int64_t k = 0; k < 10; ++k) CHECK(sorted[static_cast<size_t>(k)] == k);  // a permutation
}

TEST_CASE("annotation project: errors name what to do", "[annotation_project]") {
  const auto& d = tiny_correspondence_data();
  const fs::path dir = scratch_dir("annotation_project_errors");
  init_annotation_project(correspondences(), (dir / "p").string());
  CHECK_THROWS_WITH(init_annotation_project(correspondences(), (dir / "p").string()),
                    Catch::Contains("already holds an annotation project") && Catch::Contains("--force"));
  AnnotationProjectOptions force;
  force.force = true;
  init_annotation_project(correspondences(), (dir / "p").string(), force);
  CHECK(AnnotationStore::open((dir / "p" / "annotations.db").string()).progress().done() == 0);
  CHECK_THROWS_WITH(init_annotation_project((dir / "none").string(), (dir / "q").string()),
                    Catch::Contains("correspondence folder not found"));

  const Correspondences c = load_correspondences(correspondences());
  Dataset human = load_dataset(d.human);
  const Dataset avatar = load_dataset(d.avatar);
  const ControllerCorrespondence table = load_controller_correspondence(d.table);
  // A face-folder dataset has no recipes, hence no ground truth.
  Dataset captured = human;
  captured.recipes.clear();
  CHECK_THROWS_WITH(ground_truth_scores(c, captured, avatar, table, d.table),
                    Catch::Contains("no expression recipes") && Catch::Contains("annotate terminal"));
  // A table for another rig.
  ControllerCorrespondence wrong = table;
  wrong["ctrlX"] = {{"a", 1.0}};
  CHECK_THROWS_WITH(ground_truth_scores(c, human, avatar, wrong, "wrong.yaml"),
                    Catch::Contains("wrong.yaml") && Catch::Contains("ctrlX"));
  ControllerCorrespondence unknown_shape = table;
  unknown_shape["ctrl3"] = {{"z", 1.0}};
  CHECK_THROWS_WITH(ground_truth_scores(c, human, avatar, unknown_shape, "shape.yaml"), Catch::Contains("\"z\""));
}

TEST_CASE("annotation project: the commands run end to end", "[annotation_project]") {
  const auto& d = tiny_correspondence_data();
  const fs::path dir = scratch_dir("annotation_project_cli");
  const std::string corr = (dir / "c").string(), project = (dir / "p").string();
  CHECK(run_cli({"correspond", "--human", d.human, "--avatar", d.avatar, "--avatar-vae", d.run, "--out", corr,
                 "--group-size", "4", "--expressions", "A,C"}) == 0);
  CHECK(load_correspondences(corr).expressions == std::vector<std::string>{"A", "C"});
  CHECK(run_cli({"annotate", "init", "--correspondences", corr, "--out", project}) == 0);
  CHECK(run_cli({"annotate", "simulate", project, "--table", d.table, "--noise", "0"}) == 0);
  CHECK(run_cli({"annotate", "progress", project}) == 0);
  const std::string csv = (dir / "triplets.csv").string();
  CHECK(run_cli({"annotate", "export", project, "--out", csv, "--no-derived"}) == 0);
  std::ifstream in(csv);
  int lines = 0;
  for (std::string line; std::getline(in, line);) ++lines;
  CHECK(lines == 1 + 2 * 3);  // header + 2 groups x 3 comparisons
  CHECK(run_cli({"annotate", "bogus"}) == 1);
  CHECK(run_cli({"annotate", "simulate", project}) == 1);  // no --table

  // The pictures a person would look at.
  AnnotationRenders renders(load_annotation_project(project), 64);
  const std::string anchor = renders.anchor("A");
  const int64_t sample = load_correspondences(corr).groups[0][0].item<int64_t>();
  const std::string candidate = renders.candidate(sample);
  CHECK(fs::exists(anchor));
  CHECK(fs::exists(candidate));
  CHECK(fs::path(candidate).parent_path() == fs::path(project) / "renders");
}

TEST_CASE("annotate simulate: the same people read the table alike in every round", "[annotation_project]") {
  // Judgements without noise, draws or lapses: the answers follow from each annotator's reading
  // of the table alone (read loosely, so that two readings tell apart on the tiny data). A round's --seed must not
  // redraw the readings; --reading-seed does.
  const auto& d = tiny_correspondence_data();
  const fs::path dir = scratch_dir("annotation_reading_seed");
  const std::string corr = (dir / "c").string();
  REQUIRE(run_cli({"correspond", "--human", d.human, "--avatar", d.avatar, "--avatar-vae", d.run, "--out", corr,
                   "--group-size", "4"}) == 0);
  const auto answers = [&](const std::string& name, const std::string& seed, const std::string& reading_seed) {
    const std::string project = (dir / name).string();
    REQUIRE(run_cli({"annotate", "init", "--correspondences", corr, "--out", project}) == 0);
    REQUIRE(run_cli({"annotate", "simulate",         project,     "--table",       d.table, "--noise",
                     "0",        "--weber",          "0",         "--draw-margin", "0",     "--draw-rate",
                     "0",        "--lapse-rate",     "0",         "--fatigue",     "0",     "--share-spread",
                     "1.5",      "--neighbour-rate", "0.5",       "--drop-rate",   "0.3",   "--seed",
                     seed,       "--reading-seed",   reading_seed}) == 0);
    std::vector<std::string> out;  // "anchor: positive > negative by annotator"
    for (const Triplet& t : AnnotationStore::open(load_annotation_project(project).database()).triplets(false))
      out.push_back(t.anchor + ": " + std::to_string(t.positive) + " > " + std::to_string(t.negative) + " by " +
                    t.annotator);
    return out;
  };
  const auto first = answers("p1", "1", "1");
  REQUIRE(!first.empty());
  for (const std::string& t : first) CHECK_THAT(t, Catch::Contains(" by simulated-"));  // who decided
  CHECK(answers("p2", "2", "1") == first);  // another round, the same people
  CHECK(answers("p3", "1", "2") != first);  // other people
}
