// retarget annotate: annotation projects over a correspondence set (correspond/annotation_project.h).
//   init      a project: one tournament per expression group
//   simulate  simulated annotators, each with its own reading of the avatar (face-model datasets)
//   terminal  a person answering in the terminal
//   serve     the web annotation tool (cli/annotate_serve_command.cpp)
//   progress  comparisons decided, champions, annotators
//   export    the triplets as CSV
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cxxopts.hpp>
#include <iostream>
#include <numeric>

#include "annotate/terminal_annotator.h"
#include "cli/command_options.h"
#include "cli/commands.h"
#include "core/error.h"
#include "core/random.h"
#include "core/timer.h"
#include "correspond/annotation_project.h"
#include "correspond/perceived_scores.h"

namespace retarget::cli {

namespace {

std::string positional_project(const cxxopts::ParseResult& args, const char* command) {
  if (!args.count("project")) throw Error(std::string("retarget annotate ") + command, "give the PROJECT folder");
  return args["project"].as<std::string>();
}

void print_progress(const AnnotationStore& store, bool per_group) {
  const StoreProgress p = store.progress();
  int champions = 0, tie_breaks = 0;
  for (const GroupProgress& g : p.groups) {
    champions += g.champion.has_value();
    tie_breaks += g.tie_breaks;
  }
  std::cout << fmt::format("  {} of {} comparisons decided ({:.1f}%), {} of {} groups have a champion, {} tie-breaks\n",
                           p.done(), p.total(), p.total() ? 100.0 * p.done() / p.total() : 100.0, champions,
                           p.groups.size(), tie_breaks);
  if (per_group) {
    size_t width = 5;
    for (const GroupProgress& g : p.groups) width = std::max(width, g.label.size());
    std::cout << fmt::format("  {:<{}}  {:>9}  {:>8}  {}\n", "group", width, "decided", "champion", "tie-breaks");
    for (const GroupProgress& g : p.groups)
      std::cout << fmt::format("  {:<{}}  {:>4}/{:<4}  {:>8}  {}\n", g.label, width, g.done, g.total,
                               g.champion ? std::to_string(*g.champion) : "-", g.tie_breaks);
  }
  for (const AnnotatorProgress& a : p.annotators)
    std::cout << fmt::format("  annotator {}: {} decided, {} draws\n", a.name, a.decided, a.draws);
}

int init(int argc, char** argv) {
  cxxopts::Options options("retarget annotate init",
                           "Make an annotation project from a correspondence folder: one tournament per expression,\n"
                           "over its group of avatar samples.");
  options.add_options()("correspondences", "the correspondence folder (retarget correspond)",
                        cxxopts::value<std::string>())("out", "the project folder to make",
                                                       cxxopts::value<std::string>())(
      "seed", "pairing seed of the tournaments and of the order the groups are handed out in (give each round its own)",
      cxxopts::value<uint64_t>()->default_value("1"))("force", "replace an existing project (its answers are lost)");
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  for (const char* required : {"correspondences", "out"})
    if (!args.count(required)) throw Error(std::string("missing --") + required + " (see --help)");
  AnnotationProjectOptions o;
  o.seed = args["seed"].as<uint64_t>();
  o.force = args.count("force") > 0;
  const AnnotationProject project =
      init_annotation_project(args["correspondences"].as<std::string>(), args["out"].as<std::string>(), o);
  AnnotationStore store = AnnotationStore::open(project.database());
  std::cout << fmt::format("annotation project {} over {} (seed {})\n", project.folder, project.correspondences,
                           project.seed);
  print_progress(store, false);
  return 0;
}

// How often the decided comparisons agree with the table itself: with the faces it gives (mm
// over the regions, read exactly) and with its rig weights, on pairs where it has a clear answer.
void print_agreement(const AnnotationStore& store, const CandidateScores& faces_mm, const GroundTruth& truth) {
  const auto agreement = [&](const CandidateScores& key, double clear_gap) {
    int agree = 0, clear = 0;
    for (const Triplet& t : store.triplets(false)) {
      const double positive = key.at(t.anchor).at(t.positive), negative = key.at(t.anchor).at(t.negative);
      if (std::abs(positive - negative) <= clear_gap) continue;
      ++clear;
      agree += positive < negative;
    }
    return clear > 0 ? fmt::format("{} of {} ({:.0f}%)", agree, clear, 100.0 * agree / clear) : std::string("-");
  };
  std::cout << fmt::format(
      "  the answers agree with the table's faces on {} clear pairs (> 0.05 mm apart), with its rig weights on {} "
      "(> 0.05 apart)\n",
      agreement(faces_mm, 0.05), agreement(truth.scores, 0.05));
}

// How good the champions are by the ground truth.
void print_champions(const AnnotationStore& store, const GroundTruth& truth, int group_size) {
  double champion_sum = 0, best_sum = 0, mean_sum = 0, nearest_sum = 0;
  int groups = 0, best_count = 0;
  std::vector<int> ranks;
  for (const GroupProgress& g : store.progress().groups) {
    if (!g.champion) continue;
    const auto& scores = truth.scores.at(g.label);
    std::vector<double> values;
    for (const auto& entry : scores) values.push_back(entry.second);
    std::sort(values.begin(), values.end());
    const double champion = scores.at(*g.champion);
    champion_sum += champion;
    best_sum += values.front();
    mean_sum += std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size());
    nearest_sum += scores.at(store.group(g.group).candidates.front());
    ranks.push_back(static_cast<int>(std::lower_bound(values.begin(), values.end(), champion) - values.begin()) + 1);
    best_count += champion == values.front();
    ++groups;
  }
  if (groups > 0) {
    std::sort(ranks.begin(), ranks.end());
    std::cout << fmt::format(
        "  ground truth (rig-weight distance, lower is better), mean over {} groups: champion {:.4f}, best candidate "
        "{:.4f}, group average {:.4f}, geometrically nearest candidate {:.4f}; the champion is the best candidate "
        "in {} groups, median rank {} of {}\n",
        groups, champion_sum / groups, best_sum / groups, mean_sum / groups, nearest_sum / groups, best_count,
        ranks[ranks.size() / 2], group_size);
  }
}

// Where the round started from (the DT result on the rig, or the previous round's outcome).
void print_start(const Correspondences& c, const GroundTruth& truth, const Dataset& avatar) {
  if (c.initial_weights.defined() && c.initial_weights.size(1) == static_cast<int64_t>(avatar.controllers.size())) {
    double start_sum = 0;
    for (int64_t k = 0; k < c.expression_count(); ++k) {
      const std::vector<double>& target = truth.controller_weights.at(c.expressions[k]);
      double sum = 0;
      for (size_t j = 0; j < target.size(); ++j)
        sum += std::pow(c.initial_weights[k][static_cast<int64_t>(j)].item<double>() - target[j], 2);
      start_sum += std::sqrt(sum);
    }
    std::cout << fmt::format("  the groups' start ({}): rig-weight distance {:.4f} on average\n", c.initial,
                             start_sum / static_cast<double>(c.expression_count()));
  }
}

int simulate(int argc, char** argv) {
  cxxopts::Options options(
      "retarget annotate simulate",
      "Answer a project's comparisons with simulated annotators. Each reads the avatar's controller\n"
      "table its own way (shares off by a factor, now and then a neighbouring shape, a controller of\n"
      "several shapes read as one, one not understood) and judges faces, not weights: a candidate's\n"
      "distance in mm over the face's regions to the avatar it imagines, with perception noise that\n"
      "grows with the difference and with fatigue, draws when faces look alike, and lapses.\n"
      "--oracle instead ranks by rig-weight distance to the table itself (the evaluation's answer key).");
  SimulatedAnnotatorOptions sim;
  ReadingOptions reading;
  options.add_options()("project", "the project folder", cxxopts::value<std::string>())(
      "table", "the avatar rig's correspondence.yaml (controllers -> human blendshapes)",
      cxxopts::value<std::string>())("noise", "noise added to each score per comparison (mm; --oracle: rig weights)",
                                     cxxopts::value<double>()->default_value("0.05"))(
      "weber", "plus this fraction of the scores' mean", cxxopts::value<double>()->default_value("0.2"))(
      "draw-margin", "draw when the noisy scores differ by at most this (mm)",
      cxxopts::value<double>()->default_value("0.02"))("draw-rate", "probability of answering draw",
                                                       cxxopts::value<double>()->default_value("0.05"))(
      "lapse-rate", "probability of a random answer", cxxopts::value<double>()->default_value("0.03"))(
      "fatigue", "noise growth per 1,000 answers of one annotator", cxxopts::value<double>()->default_value("0.5"))(
      "share-spread", "log-normal spread of each annotator's reading of a share",
      cxxopts::value<double>()->default_value("0.3"))("neighbour-rate",
                                                      "probability a share is read as a neighbouring shape",
                                                      cxxopts::value<double>()->default_value("0.1"))(
      "reread-rate", "probability a controller of several shapes is read as one of them",
      cxxopts::value<double>()->default_value("0.3"))("drop-rate", "probability a controller is not understood",
                                                      cxxopts::value<double>()->default_value("0.05"))(
      "oracle", "rank by rig-weight distance to the table itself, noise --noise, draws --draw-rate only")(
      "budget", "stop after this many answers in all (0: finish every tournament)",
      cxxopts::value<int64_t>()->default_value("0"))(
      "annotators",
      "simulated annotators taking turns (a budget spread over six people: about 330 answers each at 2,000)",
      cxxopts::value<int>()->default_value("6"))("seed", "seed of the simulated answers (a round's own)",
                                                 cxxopts::value<uint64_t>()->default_value("1"))(
      "reading-seed",
      "seed of the annotators' readings of the table: the same people, each with the same reading, in every round "
      "that shares it",
      cxxopts::value<uint64_t>()->default_value("1"))("name", "annotator name (name-1 .. name-N for several)",
                                                      cxxopts::value<std::string>()->default_value(sim.name));
  options.parse_positional({"project"});
  options.positional_help("PROJECT --table RIG/correspondence.yaml");
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  const std::string folder = positional_project(args, "simulate");
  if (!args.count("table")) throw Error("missing --table RIG/correspondence.yaml (see --help)");
  const bool oracle = args.count("oracle") > 0;
  sim.noise = args["noise"].as<double>();
  sim.draw_rate = args["draw-rate"].as<double>();
  if (!oracle) {
    sim.weber = args["weber"].as<double>();
    sim.draw_margin = args["draw-margin"].as<double>();
    sim.lapse_rate = args["lapse-rate"].as<double>();
    sim.fatigue = args["fatigue"].as<double>();
  }
  sim.annotators = args["annotators"].as<int>();
  sim.seed = args["seed"].as<uint64_t>();
  const uint64_t reading_seed = args["reading-seed"].as<uint64_t>();
  sim.name = args["name"].as<std::string>();
  sim.validate("simulate");
  reading.share_spread = args["share-spread"].as<double>();
  reading.neighbour_rate = args["neighbour-rate"].as<double>();
  reading.reread_rate = args["reread-rate"].as<double>();
  reading.drop_rate = args["drop-rate"].as<double>();
  reading.validate("simulate");
  const int64_t budget = args["budget"].as<int64_t>();
  if (budget < 0) throw Error("--budget", fmt::format("expected 0 or more answers, got {}", budget));

  const Stopwatch clock;
  const AnnotationProject project = load_annotation_project(folder);
  const Correspondences c = load_correspondences(project.correspondences);
  const Dataset human = load_dataset(c.human_dataset);
  const Dataset avatar = load_dataset(c.avatar_dataset);
  check_correspondences(c, human, avatar);
  const std::string table_path = args["table"].as<std::string>();
  const ControllerCorrespondence table = load_controller_correspondence(table_path);
  // The table's own distances: the oracle's scores, and below, how good the champions are.
  const GroundTruth truth = ground_truth_scores(c, human, avatar, table, table_path);
  // Each annotator's own reading and, last, the table read exactly: the faces the table itself
  // makes, for the agreement printed below (one pass over the candidates' meshes for all).
  std::vector<ControllerCorrespondence> readings;
  if (!oracle) {
    const std::vector<std::string> shapes = blendshape_names(human.source);
    for (int i = 0; i < sim.annotators; ++i)
      readings.push_back(
          annotator_reading(table, shapes, reading, mix_seed(reading_seed, 0x7eadU, static_cast<uint64_t>(i))));
  }
  readings.push_back(table);
  std::vector<CandidateScores> scores = perceived_scores(c, human, avatar, readings);
  const CandidateScores faces_mm = std::move(scores.back());
  scores.pop_back();
  if (oracle) scores.assign(static_cast<size_t>(sim.annotators), truth.scores);
  const double setup_seconds = clock.seconds();

  AnnotationStore store = AnnotationStore::open(project.database());
  const SimulationCounts counts = run_simulated_annotation(store, scores, sim, budget);
  std::cout << fmt::format(
      "simulated {} {} annotator{} on {} (noise {}, draw rate {}): {} answers, {} decided, {} draws, {} tie-breaks; "
      "{:.2f} s ({:.2f} s reading the data){}\n",
      sim.annotators, oracle ? "oracle" : "people-like", sim.annotators == 1 ? "" : "s", project.folder, sim.noise,
      sim.draw_rate, counts.answers, counts.decided, counts.draws, counts.tie_breaks, clock.seconds(), setup_seconds,
      counts.finished ? "" : "; the budget ran out before every tournament finished");
  print_progress(store, false);

  print_agreement(store, faces_mm, truth);
  print_champions(store, truth, c.group_size);
  print_start(c, truth, avatar);
  return 0;
}

int terminal(int argc, char** argv) {
  cxxopts::Options options("retarget annotate terminal",
                           "Answer a project's comparisons in the terminal: for each, look at the human expression\n"
                           "and the two avatar candidates (PNG files, rendered into PROJECT/renders/ on first use)\n"
                           "and type 1 (left is more alike), 2 (right), d (draw), u (undo) or q (quit).");
  options.add_options()("project", "the project folder", cxxopts::value<std::string>())("name", "your annotator name",
                                                                                        cxxopts::value<std::string>())(
      "no-render", "show mesh files (reference/<expression>.obj) and sample ids instead of pictures")(
      "size", "picture size in pixels", cxxopts::value<int>()->default_value("384"));
  options.parse_positional({"project"});
  options.positional_help("PROJECT --name NAME");
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  const std::string folder = positional_project(args, "terminal");
  if (!args.count("name")) throw Error("missing --name NAME (see --help)");
  const AnnotationProject project = load_annotation_project(folder);
  RenderPaths paths;
  std::shared_ptr<AnnotationRenders> renders;
  if (args.count("no-render")) {
    const std::string reference = project.correspondences + "/reference/";
    paths.anchor = [reference](const std::string& label) { return reference + label + ".obj"; };
    paths.candidate = [](int64_t sample) { return "avatar sample " + std::to_string(sample); };
  } else {
    renders = std::make_shared<AnnotationRenders>(project, args["size"].as<int>());
    paths.anchor = [renders](const std::string& label) { return renders->anchor(label); };
    paths.candidate = [renders](int64_t sample) { return renders->candidate(sample); };
  }
  AnnotationStore store = AnnotationStore::open(project.database());
  std::cout << fmt::format("annotation project {}\n", project.folder);
  print_progress(store, false);
  const TerminalSession s = run_terminal_annotator(store, args["name"].as<std::string>(), paths, std::cin, std::cout);
  std::cout << fmt::format("session: {} decided, {} draws, {} undone{}\n", s.decided, s.draws, s.undone,
                           s.quit ? "" : "; nothing left to compare for now");
  print_progress(store, false);
  return 0;
}

int progress(int argc, char** argv) {
  cxxopts::Options options("retarget annotate progress", "Comparisons decided per group, champions and annotators.");
  options.add_options()("project", "the project folder", cxxopts::value<std::string>());
  options.parse_positional({"project"});
  options.positional_help("PROJECT");
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  const AnnotationProject project = load_annotation_project(positional_project(args, "progress"));
  AnnotationStore store = AnnotationStore::open(project.database());
  std::cout << fmt::format("annotation project {} over {}\n", project.folder, project.correspondences);
  print_progress(store, true);
  return 0;
}

int export_triplets(int argc, char** argv) {
  cxxopts::Options options(
      "retarget annotate export",
      "Write the project's triplets (group, anchor, positive, negative, derived, tie_break) as CSV.");
  options.add_options()("project", "the project folder", cxxopts::value<std::string>())("out", "the CSV file to write",
                                                                                        cxxopts::value<std::string>())(
      "no-derived", "only the comparisons answered, not the ones that follow by transitivity");
  options.parse_positional({"project"});
  options.positional_help("PROJECT --out triplets.csv");
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  const AnnotationProject project = load_annotation_project(positional_project(args, "export"));
  if (!args.count("out")) throw Error("missing --out FILE.csv (see --help)");
  const bool derived = args.count("no-derived") == 0;
  AnnotationStore store = AnnotationStore::open(project.database());
  const std::string out = args["out"].as<std::string>();
  store.export_csv(out, derived);
  const std::vector<Triplet> triplets = store.triplets(derived);
  const auto derived_count =
      std::count_if(triplets.begin(), triplets.end(), [](const Triplet& t) { return t.derived; });
  std::cout << fmt::format("{}: {} triplets ({} answered, {} derived)\n", out, triplets.size(),
                           static_cast<int64_t>(triplets.size()) - derived_count, derived_count);
  return 0;
}

void annotate_usage(std::ostream& out) {
  out << "Usage: retarget annotate SUBCOMMAND [options]\n\n"
         "  init      --correspondences C --out PROJECT [--seed 1] [--force]\n"
         "  simulate  PROJECT --table RIG/correspondence.yaml [--noise 0.05] [--draw-rate 0.05] [--annotators 2]\n"
         "  terminal  PROJECT --name NAME\n"
         "  serve     PROJECT [--port 8080] [--password P]  |  serve --demo\n"
         "  progress  PROJECT\n"
         "  export    PROJECT --out triplets.csv [--no-derived]\n\n"
         "'retarget annotate SUBCOMMAND --help' describes each.\n";
}

}  // namespace

int annotate_command(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    annotate_usage(std::cout);
    return argc < 2 ? 2 : 0;
  }
  const std::string sub = argv[1];
  if (sub == "init") return init(argc - 1, argv + 1);
  if (sub == "simulate") return simulate(argc - 1, argv + 1);
  if (sub == "terminal") return terminal(argc - 1, argv + 1);
  if (sub == "serve") return annotate_serve(argc - 1, argv + 1);
  if (sub == "progress") return progress(argc - 1, argv + 1);
  if (sub == "export") return export_triplets(argc - 1, argv + 1);
  annotate_usage(std::cerr);
  throw Error("unknown subcommand '" + sub + "'");
}

}  // namespace retarget::cli
