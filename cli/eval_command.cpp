// `retarget eval vae RUN [--checkpoint best|last] [--split test|train|all]`
#include <fmt/format.h>

#include <cmath>
#include <cxxopts.hpp>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <set>

#include "cli/command_options.h"
#include "cli/commands.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/progress.h"
#include "data/test_faces.h"
#include "eval/code_embedding.h"
#include "eval/retarget_evaluation.h"
#include "eval/vae_evaluation.h"
#include "eval/weight_recovery.h"
#include "geometry/rig.h"
#include "train/vae_run.h"

namespace retarget::cli {

namespace fs = std::filesystem;

namespace {

nlohmann::json number_or_null(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(); }

int eval_vae(int argc, char** argv) {
  cxxopts::Options options("retarget eval vae",
                           "Reconstruction error of a trained VAE in mm (eye distance scaled to 10 cm), through\n"
                           "features -> VAE -> features -> mesh, beside the trivial answers scored the same way (the\n"
                           "neutral mesh; for a human VAE also the mean expression), over every vertex and over the\n"
                           "vertices expressions move. Writes RUN/eval-<checkpoint>-<split>.json.");
  options.add_options()("run", "run folder", cxxopts::value<std::string>())(
      "checkpoint", "best or last", cxxopts::value<std::string>()->default_value("best"))(
      "split", "test, train or all", cxxopts::value<std::string>()->default_value("test"))(
      "no-anchors", "avatars: let the still vertices move when rebuilding meshes (they are held at rest by default)")(
      "no-part-motion", "avatars: keep the rigid parts (eyeballs, teeth) at rest instead of moving them with the rig");
  options.parse_positional({"run"});
  options.positional_help("RUN");
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  if (!args.count("run")) throw Error("retarget eval vae", "expected a run folder (see --help)");
  const std::string which = args["checkpoint"].as<std::string>();
  TrainedVae trained = load_trained_vae(args["run"].as<std::string>(), which);
  VaeEvaluationOptions eval_options;
  eval_options.split = args["split"].as<std::string>();
  eval_options.target_normaliser = trained.config.data.target_normaliser;
  eval_options.anchors = args.count("no-anchors") == 0;
  eval_options.part_motion = args.count("no-part-motion") == 0;
  const VaeEvaluation r = evaluate_vae(*trained.vae, trained.dataset, eval_options);

  std::cout << fmt::format(
      "{} ({} checkpoint, epoch {}) on the {} split of {}: {} samples, {} vertices\n"
      "  per-vertex error: mean {:.3f} {}, max {:.3f} {} (sample {}, vertex {}), mean of per-sample max {:.3f} {}\n"
      "  ground truth: {}; normalised feature L1 {:.5f}; {}\n",
      trained.folder, which, trained.state.epoch, r.split, trained.dataset.folder, r.samples, r.vertices, r.mean,
      r.unit, r.max, r.unit, r.worst_sample, r.worst_vertex, r.mean_of_max, r.unit, r.ground_truth, r.feature_l1,
      format_duration(r.seconds));
  // The VAE beside the trivial answers, in the same metric.
  std::cout << fmt::format("  moving vertices: {} of {} (from the {}); beside the trivial answers:\n",
                           r.moving_vertices, r.vertices, r.footprint);
  std::cout << fmt::format("  {:<16}{:>10}{:>14}{:>14}{:>12}{:>11}\n", "answer", "mean " + r.unit, "moving " + r.unit,
                           "mean of max", "feature L1", "x neutral");
  const TrivialScore* neutral = r.trivial_answer("neutral");
  auto row = [&](const std::string& name, double mean, double moving, double mean_of_max, double l1) {
    const double fraction = neutral && neutral->mean > 0 ? mean / neutral->mean : std::nan("");
    std::cout << fmt::format("  {:<16}{:>10.3f}{:>14.3f}{:>14.3f}{:>12.5f}{:>11}\n", name, mean, moving, mean_of_max,
                             l1, std::isfinite(fraction) ? fmt::format("{:.2f}", fraction) : std::string("-"));
  };
  row("vae", r.mean, r.moving_mean, r.mean_of_max, r.feature_l1);
  for (const TrivialScore& t : r.trivial)
    row(t.name == "mean_expression" ? "mean expression" : t.name, t.mean, t.moving_mean, t.mean_of_max, t.feature_l1);
  if (std::isfinite(r.fraction_of_neutral) && std::isfinite(r.moving_fraction_of_neutral))
    std::cout << fmt::format(
        "  the VAE's error is x{:.2f} the neutral answer's over every vertex, x{:.2f} over the "
        "moving ones{}\n",
        r.fraction_of_neutral, r.moving_fraction_of_neutral,
        r.moving_fraction_of_neutral < 1 ? "" : ": it does not beat doing nothing");
  if (const TrivialScore* mean = r.trivial_answer("mean_expression"); mean && mean->moving_mean > 0)
    std::cout << fmt::format("  and x{:.2f} the mean expression's over the moving vertices{}\n",
                             r.moving_mean / mean->moving_mean,
                             r.moving_mean < mean->moving_mean ? "" : ": it does not beat one fixed expression");
  if (!r.region_mean.empty()) {
    const TrivialScore* neutral = r.trivial_answer("neutral");
    std::cout << "  per region, " << r.unit << " (neutral answer):";
    for (const auto& [region, mean] : r.region_mean) {
      const auto it = neutral ? neutral->region_mean.find(region) : std::map<std::string, double>::const_iterator();
      std::cout << fmt::format(" {} {:.3f}", region, mean);
      if (neutral && it != neutral->region_mean.end()) std::cout << fmt::format(" ({:.3f})", it->second);
      std::cout << ";";
    }
    std::cout << "\n";
  }
  if (std::isfinite(r.code_distance_ratio)) {
    std::cout << fmt::format(
        "  codes of the same expression across people: mean distance {:.4f}; between expressions {:.4f}; ratio "
        "{:.3f}\n",
        r.within_expression, r.between_expression, r.code_distance_ratio);
  }
  nlohmann::ordered_json report;
  report["run"] = trained.folder;
  report["checkpoint"] = which;
  report["epoch"] = trained.state.epoch;
  report["dataset"] = trained.dataset.folder;
  report["split"] = r.split;
  report["samples"] = r.samples;
  report["vertices"] = r.vertices;
  report["unit"] = r.unit;
  report["mm_per_unit"] = r.unit_scale;
  report["ground_truth"] = r.ground_truth;
  report["mean"] = r.mean;
  report["max"] = r.max;
  report["mean_of_max"] = r.mean_of_max;
  report["worst_sample"] = r.worst_sample;
  report["worst_vertex"] = r.worst_vertex;
  report["feature_l1"] = r.feature_l1;
  report["within_expression"] = number_or_null(r.within_expression);
  report["between_expression"] = number_or_null(r.between_expression);
  report["code_distance_ratio"] = number_or_null(r.code_distance_ratio);
  report["footprint"] = r.footprint;
  report["moving_vertices"] = r.moving_vertices;
  report["moving_mean"] = r.moving_mean;
  report["region_mean"] = r.region_mean;
  report["fraction_of_neutral"] = number_or_null(r.fraction_of_neutral);
  report["moving_fraction_of_neutral"] = number_or_null(r.moving_fraction_of_neutral);
  nlohmann::ordered_json trivial = nlohmann::ordered_json::object();
  for (const TrivialScore& t : r.trivial) {
    nlohmann::ordered_json answer;
    answer["mean"] = t.mean;
    answer["max"] = t.max;
    answer["mean_of_max"] = t.mean_of_max;
    answer["moving_mean"] = t.moving_mean;
    answer["region_mean"] = t.region_mean;
    answer["feature_l1"] = t.feature_l1;
    trivial[t.name] = std::move(answer);
  }
  report["trivial"] = std::move(trivial);
  const std::string path = (fs::path(trained.folder) / fmt::format("eval-{}-{}.json", which, r.split)).string();
  write_file_atomically(path, [&](std::ostream& out) { out << report.dump(2) << "\n"; });
  std::cout << "  written: " << path << "\n";
  // Training and test codes on their two principal axes, for `retarget plot RUN` (codes.png).
  const CodeEmbedding codes =
      write_code_embedding(*trained.vae, trained.dataset, (fs::path(trained.folder) / "codes.tsv").string());
  std::cout << fmt::format("  written: {} ({} training and {} test codes; the two axes hold {:.0f}% of the variance)\n",
                           codes.path, codes.train, codes.test, 100 * codes.explained);
  return 0;
}

// One row per method: mm over all and moving vertices, rig-weight errors, each beside the
// neutral answer's (xN), and per region.
void print_scores(const std::vector<MethodScore>& methods) {
  const auto fraction = [](double f) { return std::isfinite(f) ? fmt::format("x{:.2f}", f) : std::string("-"); };
  std::cout << fmt::format("{:<12}{:>9}{:>7}{:>11}{:>7}{:>9}{:>10}{:>11}{:>7}{:>10}", "method", "mean mm", "",
                           "moving mm", "", "max mm", "weights", "active w", "", "rel. w");
  std::set<std::string> regions;
  for (const MethodScore& s : methods)
    for (const auto& entry : s.region_mm) regions.insert(entry.first);
  for (const std::string& region : regions) std::cout << fmt::format("{:>9}", region);
  std::cout << "\n";
  for (const MethodScore& s : methods) {
    std::cout << fmt::format("{:<12}{:>9.3f}{:>7}{:>11.3f}{:>7}{:>9.2f}{:>10.4f}{:>11.4f}{:>7}{:>10.3f}", s.name,
                             s.mean_mm, fraction(s.fraction_of_neutral), s.moving_mm,
                             fraction(s.moving_fraction_of_neutral), s.max_mm, s.weight_error, s.weight_error_active,
                             fraction(s.weight_active_fraction_of_neutral), s.weight_error_relative);
    for (const std::string& region : regions) {
      const auto it = s.region_mm.find(region);
      std::cout << (it == s.region_mm.end() ? fmt::format("{:>9}", "-") : fmt::format("{:>9.3f}", it->second));
    }
    std::cout << "\n";
  }
}

int eval_retarget(int argc, char** argv) {
  cxxopts::Options options(
      "retarget eval retarget",
      "The end-to-end check on faces with ground truth: each method's avatar meshes (folders of\n"
      "retarget-infer output, NAME=FOLDER) and deformation transfer alone against the rig expression\n"
      "the controller table gives for each face's recipe. Writes OUT/metrics.json (mm and rig-weight\n"
      "errors per method), OUT/comparison.csv (a row per method and set), OUT/contact_sheet.png (human |\n"
      "methods | ground truth) and OUT/dt/.");
  RetargetEvaluationOptions eval;
  options.add_options()("faces", "folder written by `retarget faces`", cxxopts::value<std::string>())(
      "correspondences", "the correspondence folder", cxxopts::value<std::string>())(
      "method", "NAME=FOLDER of avatar meshes (repeatable)", cxxopts::value<std::vector<std::string>>())(
      "no-dt", "leave out deformation transfer alone")(
      "table", "controller table (default: correspondence.yaml beside the rig)", cxxopts::value<std::string>())(
      "no-neutral", "leave out the neutral answer (the avatar's rest mesh for every face)")(
      "no-rig-projection", "leave out DT projected onto the rig (dt_rig)")("sheet-rows", "faces on the contact sheet",
                                                                           cxxopts::value<int>()->default_value("8"))(
      "sheet", "worst (the worst expressions of --sheet-method) or first",
      cxxopts::value<std::string>()->default_value("worst"))(
      "sheet-method", "the method whose worst faces the sheet shows (default: the last)",
      cxxopts::value<std::string>())("out", "output folder", cxxopts::value<std::string>());
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  if (args.count("faces")) eval.faces = args["faces"].as<std::string>();
  if (args.count("correspondences")) eval.correspondences = args["correspondences"].as<std::string>();
  if (args.count("out")) eval.out = args["out"].as<std::string>();
  if (args.count("table")) eval.table = args["table"].as<std::string>();
  eval.deformation_transfer = args.count("no-dt") == 0;
  eval.neutral = args.count("no-neutral") == 0;
  eval.rig_projection = args.count("no-rig-projection") == 0;
  eval.sheet_rows = args["sheet-rows"].as<int>();
  eval.sheet = args["sheet"].as<std::string>();
  if (args.count("sheet-method")) eval.sheet_method = args["sheet-method"].as<std::string>();
  if (args.count("method"))
    for (const std::string& m : args["method"].as<std::vector<std::string>>()) {
      const size_t eq = m.find('=');
      if (eq == std::string::npos) throw Error("--method " + m, "expected NAME=FOLDER");
      eval.methods.emplace_back(m.substr(0, eq), m.substr(eq + 1));
    }
  const RetargetEvaluation r = evaluate_retargeting(eval);
  if (r.ground_truth) {
    std::cout << fmt::format("{} moving vertices; regions:", r.moving_vertices);
    for (const auto& [region, count] : r.region_vertices) std::cout << fmt::format(" {} {}", region, count);
    std::cout << "\n";
    print_scores(r.methods);
    for (const char* set : {kReferenceSet, kBlendSet}) {
      const auto it = r.sets.find(set);
      if (it == r.sets.end()) continue;
      std::cout << fmt::format("\n{} only ({} faces):\n", set, it->second.front().samples);
      print_scores(it->second);
    }
    // Per expression: the moving-vertex error of every method, so a failure is visible.
    std::cout << fmt::format("\nper expression, moving-vertex mean mm:\n{:<22}", "expression");
    for (const MethodScore& s : r.methods) std::cout << fmt::format("{:>10}", s.name.substr(0, 9));
    std::cout << "\n";
    for (const auto& entry : r.methods.front().expression_moving_mm) {
      std::cout << fmt::format("{:<22}", entry.first.substr(0, 21));
      for (const MethodScore& s : r.methods)
        std::cout << fmt::format("{:>10.3f}", s.expression_moving_mm.at(entry.first));
      std::cout << "\n";
    }
    std::cout << "contact sheet: " << fmt::format("{}", fmt::join(r.sheet_expressions, ", ")) << "\n";
  } else {
    std::cout << "no ground truth for these faces (no recipe weights): contact sheet only\n";
  }
  std::cout << fmt::format("  written: {}, {} ({})\n", r.metrics_path, r.sheet_path, format_duration(r.seconds));
  return 0;
}

int eval_weights(int argc, char** argv) {
  cxxopts::Options options(
      "retarget eval weights",
      "How well the rig's weights come back through the runtime's own path, before any network:\n"
      "the rig's own expressions as DR features, rebuilt as the bundle rebuilds avatar meshes, solved\n"
      "for weights as retarget-infer --weights does. A floor for --weights on this rig.");
  options.add_options()("rig", "the avatar's rig (folder, rig.yaml or .glb)", cxxopts::value<std::string>())(
      "mesh", "glTF only: the mesh with the morph targets", cxxopts::value<std::string>())(
      "samples", "expressions (1-5 controllers each)", cxxopts::value<int>()->default_value("100"))(
      "seed", "random seed", cxxopts::value<uint64_t>()->default_value("1"))(
      "ridge", "towards the neutral, as retarget-infer --weights-ridge",
      cxxopts::value<double>()->default_value("1e-4"))("no-part-motion", "keep the rigid parts at rest");
  options.parse_positional({"rig"});
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  if (!args.count("rig")) throw Error("retarget eval weights", "missing the rig (see --help)");
  const Rig rig = load_rig(args["rig"].as<std::string>(), args.count("mesh") ? args["mesh"].as<std::string>() : "");
  WeightRecoveryOptions o;
  o.samples = args["samples"].as<int>();
  o.seed = args["seed"].as<uint64_t>();
  o.ridge = args["ridge"].as<double>();
  o.part_motion = args.count("no-part-motion") == 0;
  const WeightRecovery r = measure_weight_recovery(rig, o);
  std::cout << fmt::format(
      "{}: {} controllers, {} samples, {} still vertices anchored, parts {}: mean absolute weight error {:.4f} "
      "(largest "
      "{:.3f}), residual {:.3f} {}\n",
      rig.source, r.controllers, r.samples, r.still_vertices, o.part_motion ? "following the rig" : "at rest",
      r.mean_abs_error, r.max_abs_error, r.residual, r.unit);
  return 0;
}

}  // namespace

int eval_command(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "-h" || std::string(argv[1]) == "--help") {
    std::cout << "Usage: retarget eval vae RUN [--checkpoint best|last] [--split test|train|all]\n"
                 "       retarget eval retarget --faces DIR --correspondences DIR --method NAME=DIR... --out DIR\n"
                 "       retarget eval ladder --correspondences DIR --translation RUN [--checkpoint last|stageN] "
                 "[--table T] [--out DIR]\n"
                 "       retarget eval weights RIG [--samples 100] [--ridge 1e-4] [--no-part-motion]\n";
    return argc < 2 ? 1 : 0;
  }
  const std::string what = argv[1];
  if (what == "vae") return eval_vae(argc - 1, argv + 1);
  if (what == "retarget") return eval_retarget(argc - 1, argv + 1);
  if (what == "ladder") return eval_ladder(argc - 1, argv + 1);
  if (what == "weights") return eval_weights(argc - 1, argv + 1);
  throw Error("retarget eval", "unknown evaluation '" + what + "' (known: vae, retarget, ladder, weights)");
}

}  // namespace retarget::cli
