// `retarget eval vae RUN [--checkpoint best|last] [--split test|train|all]`
#include <fmt/format.h>

#include <cmath>
#include <cxxopts.hpp>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/progress.h"
#include "train/commands.h"
#include "train/retarget_evaluation.h"
#include "train/vae_evaluation.h"
#include "train/vae_run.h"

namespace retarget::cli {

namespace fs = std::filesystem;

namespace {

nlohmann::json number_or_null(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(); }

int eval_vae(int argc, char** argv) {
  cxxopts::Options options("retarget eval vae",
                           "Reconstruction error of a trained VAE in mm (eye distance scaled to 10 cm), through\n"
                           "features -> VAE -> features -> mesh. Writes RUN/eval-<checkpoint>-<split>.json.");
  options.add_options()("run", "run folder", cxxopts::value<std::string>())(
      "checkpoint", "best or last", cxxopts::value<std::string>()->default_value("best"))(
      "split", "test, train or all", cxxopts::value<std::string>()->default_value("test"))("h,help", "show this help");
  options.parse_positional({"run"});
  options.positional_help("RUN");
  const cxxopts::ParseResult args = options.parse(argc, argv);
  if (args.count("help")) {
    std::cout << options.help() << "\n";
    return 0;
  }
  if (!args.count("run")) throw Error("retarget eval vae", "expected a run folder (see --help)");
  const std::string which = args["checkpoint"].as<std::string>();
  TrainedVae trained = load_trained_vae(args["run"].as<std::string>(), which);
  VaeEvaluationOptions eval_options;
  eval_options.split = args["split"].as<std::string>();
  const VaeEvaluation r = evaluate_vae(*trained.vae, trained.dataset, eval_options);

  std::cout << fmt::format(
      "{} ({} checkpoint, epoch {}) on the {} split of {}: {} samples, {} vertices\n"
      "  per-vertex error: mean {:.3f} {}, max {:.3f} {} (sample {}, vertex {}), mean of per-sample max {:.3f} {}\n"
      "  ground truth: {}; normalised feature L1 {:.5f}; {}\n",
      trained.folder, which, trained.state.epoch, r.split, trained.dataset.folder, r.samples, r.vertices, r.mean,
      r.unit, r.max, r.unit, r.worst_sample, r.worst_vertex, r.mean_of_max, r.unit, r.ground_truth, r.feature_l1,
      format_duration(r.seconds));
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
  const std::string path = (fs::path(trained.folder) / fmt::format("eval-{}-{}.json", which, r.split)).string();
  write_file_atomically(path, [&](std::ostream& out) { out << report.dump(2) << "\n"; });
  std::cout << "  written: " << path << "\n";
  return 0;
}

int eval_retarget(int argc, char** argv) {
  cxxopts::Options options(
      "retarget eval retarget",
      "The end-to-end check on faces with ground truth: each method's avatar meshes (folders of\n"
      "retarget-infer output, NAME=FOLDER) and deformation transfer alone against the rig expression\n"
      "the controller table gives for each face's recipe. Writes OUT/metrics.json (mm and rig-weight\n"
      "errors per method), OUT/contact_sheet.png (human | methods | ground truth) and OUT/dt/.");
  RetargetEvaluationOptions eval;
  options.add_options()("faces", "folder written by `retarget faces`", cxxopts::value<std::string>())(
      "correspondences", "the correspondence folder", cxxopts::value<std::string>())(
      "method", "NAME=FOLDER of avatar meshes (repeatable)", cxxopts::value<std::vector<std::string>>())(
      "no-dt", "leave out deformation transfer alone")(
      "table", "controller table (default: correspondence.yaml beside the rig)", cxxopts::value<std::string>())(
      "sheet-rows", "faces on the contact sheet", cxxopts::value<int>()->default_value("8"))(
      "out", "output folder", cxxopts::value<std::string>())("h,help", "show this help");
  const cxxopts::ParseResult args = options.parse(argc, argv);
  if (args.count("help")) {
    std::cout << options.help() << "\n";
    return 0;
  }
  if (args.count("faces")) eval.faces = args["faces"].as<std::string>();
  if (args.count("correspondences")) eval.correspondences = args["correspondences"].as<std::string>();
  if (args.count("out")) eval.out = args["out"].as<std::string>();
  if (args.count("table")) eval.table = args["table"].as<std::string>();
  eval.deformation_transfer = args.count("no-dt") == 0;
  eval.sheet_rows = args["sheet-rows"].as<int>();
  if (args.count("method"))
    for (const std::string& m : args["method"].as<std::vector<std::string>>()) {
      const size_t eq = m.find('=');
      if (eq == std::string::npos) throw Error("--method " + m, "expected NAME=FOLDER");
      eval.methods.emplace_back(m.substr(0, eq), m.substr(eq + 1));
    }
  const RetargetEvaluation r = evaluate_retargeting(eval);
  if (r.ground_truth) {
    std::cout << fmt::format("{:<12}{:>10}{:>10}{:>14}{:>14}\n", "method", "mean mm", "max mm", "mean max mm",
                             "weight error");
    for (const MethodScore& s : r.methods)
      std::cout << fmt::format("{:<12}{:>10.3f}{:>10.2f}{:>14.2f}{:>14.4f}\n", s.name, s.mean_mm, s.max_mm,
                               s.mean_of_max_mm, s.weight_error);
  } else {
    std::cout << "no ground truth for these faces (no recipe weights): contact sheet only\n";
  }
  std::cout << fmt::format("  written: {}, {} ({})\n", r.metrics_path, r.sheet_path, format_duration(r.seconds));
  return 0;
}

}  // namespace

int eval_command(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "-h" || std::string(argv[1]) == "--help") {
    std::cout << "Usage: retarget eval vae RUN [--checkpoint best|last] [--split test|train|all]\n"
                 "       retarget eval retarget --faces DIR --correspondences DIR --method NAME=DIR... --out DIR\n";
    return argc < 2 ? 1 : 0;
  }
  const std::string what = argv[1];
  if (what == "vae") return eval_vae(argc - 1, argv + 1);
  if (what == "retarget") return eval_retarget(argc - 1, argv + 1);
  throw Error("retarget eval", "unknown evaluation '" + what + "' (known: vae, retarget)");
}

}  // namespace retarget::cli
