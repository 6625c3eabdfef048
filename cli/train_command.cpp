// `retarget train CONFIG --out RUN [--set key.path=value ...] [--resume | --force]`
#include <fmt/format.h>

#include <cmath>
#include <cxxopts.hpp>
#include <filesystem>
#include <iostream>

#include "cli/command_options.h"
#include "cli/commands.h"
#include "cli/train_launcher.h"
#include "core/error.h"
#include "core/log.h"
#include "core/progress.h"
#include "train/data_parallel.h"
#include "train/vae_trainer.h"
#include "translate/cyclegan_trainer.h"
#include "translate/translation_trainer.h"

namespace retarget::cli {

namespace fs = std::filesystem;

namespace {

int report_cyclegan(const ConfigNode& root, RunStart start) {
  CycleGanTrainOptions train_options;
  train_options.start = start;
  const CycleGanTrainSummary s = train_cyclegan(read_cyclegan_train_config(root), train_options);
  std::cout << fmt::format(
      "{}: {} epochs{} in {}; {} human and {} avatar codes, unpaired\n"
      "  light-field similarity: held-out mean squared error {:.4g} (predicting the mean: {:.4g}) over {} pairs\n",
      s.folder, s.epochs_done, s.finished ? "" : " (not finished)", format_duration(s.seconds), s.human_codes,
      s.avatar_codes, s.fit.held_out_mse, s.fit.held_out_mean_mse, s.fit.pairs);
  if (s.epochs_run > 0)
    std::cout << fmt::format(
        "  cycle loss {:.4g} after epoch {} -> {:.4g} after epoch {}; similarity {:.4g} -> {:.4g}\n", s.first.cycle,
        s.first.epoch, s.last.cycle, s.last.epoch, s.first.similarity, s.last.similarity);
  std::cout << fmt::format("  checkpoint: {}/checkpoints/last.pt, metrics: {}/metrics.{{jsonl,csv}}\n", s.folder,
                           s.folder);
  if (s.finished) std::cout << fmt::format("  next: retarget export {} --out DIR\n", s.folder);
  return 0;
}

// The command line without --nproc (for the workers the launcher starts): "train" and its
// arguments (argv[0] is the command's name).
std::vector<std::string> without_nproc(int argc, char** argv) {
  std::vector<std::string> args{"train"};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--nproc") {
      ++i;
      continue;
    }
    if (a.rfind("--nproc=", 0) == 0) continue;
    args.push_back(a);
  }
  return args;
}

// The data-parallel group this process belongs to (torchrun's variables), or null. A rank other
// than 0 logs warnings and errors only.
DataParallelPtr join_data_parallel() {
  const DataParallelEnv env = data_parallel_env_from_environment();
  if (!env.distributed()) return nullptr;
  if (env.rank != 0) log::set_level(std::max(log::level(), log::Level::warn));
  return std::make_shared<DataParallel>(env);
}

}  // namespace

int train_command(int argc, char** argv) {
  const std::vector<std::string> worker_args = without_nproc(argc, argv);
  const std::vector<std::string> overrides = take_overrides("retarget train", argc, argv);
  cxxopts::Options options(
      "retarget train",
      "Trains what a YAML config names (task: vae, translation or cyclegan) into the run folder --out. The profiles\n"
      "under configs/train (a base: file plus what a profile changes) name no run's files: give the run\n"
      "folder with --out and the data with --set.\n"
      "  retarget train configs/train/quick/avatar_vae.yaml --set data.dataset=out/demo/datasets/avatar \\\n"
      "    --out out/demo/runs/avatar_vae\n"
      "  retarget train configs/train/quick/translation.yaml --set data.human_vae=RUN --set data.avatar_vae=RUN \\\n"
      "    --set data.correspondences=CORR [--set data.triplets=PROJECT] --out out/demo/runs/translation\n"
      "  retarget train configs/train/quick/cyclegan.yaml --set data.human_vae=RUN --set data.avatar_vae=RUN \\\n"
      "    --out out/demo/method/cyclegan      (the CycleGAN+LFD baseline)\n"
      "  retarget train out/runs/fox-vae --resume     (a run folder: its own config)");
  options.add_options()("config", "config file (or, with --resume, a run folder)", cxxopts::value<std::string>())(
      "out", "the run folder (the config's `output`, as --set output=DIR)", cxxopts::value<std::string>())(
      "resume", "continue the unfinished run in the output folder from its last checkpoint")(
      "force", "delete an existing run in the output folder and start again")(
      "nproc",
      "data-parallel: start N local workers (as torchrun does; a run started by torchrun needs no option), "
      "gradients summed through Gloo, rank 0 writing the run folder",
      cxxopts::value<int>())(
      "set",
      "override a config value with YAML, e.g. --set training.epochs=5 or --set 'model.channels=[9, 32, 1]' "
      "(repeatable)");
  options.parse_positional({"config"});
  options.positional_help("CONFIG --out RUN");
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  if (!args.count("config")) throw Error("retarget train", "expected a config file (see --help)");
  if (args.count("resume") && args.count("force"))
    throw Error("retarget train", "--resume and --force exclude each other");
  if (args.count("nproc")) {
    if (std::getenv("WORLD_SIZE"))
      throw Error("--nproc", "this process is already a data-parallel worker (WORLD_SIZE is set)");
    return launch_local_workers(args["nproc"].as<int>(), worker_args);
  }
  std::string path = args["config"].as<std::string>();
  if (fs::is_directory(path)) {
    if (!args.count("resume")) throw Error(path, "is a folder; give a config file, or a run folder with --resume");
    path = (fs::path(path) / "config.yaml").string();
  }
  const std::string out = args.count("out") ? args["out"].as<std::string>() : "";
  if (args.count("out")) {
    if (out.empty()) throw Error("--out", "expected a run folder, got \"\"");
    for (const std::string& assignment : overrides)
      if (assignment.rfind("output=", 0) == 0)
        throw Error("retarget train", "--out and --set " + assignment + " both name the run folder; give one");
  }
  ConfigNode root = load_config_with_overrides(path, overrides);
  if (!out.empty()) root.override_string("output", out, "--out " + out);
  const std::string task = config_task(root);
  const DataParallelPtr parallel = join_data_parallel();
  if (parallel && task == "cyclegan")
    throw Error("retarget train", "data-parallel training (WORLD_SIZE " + std::to_string(parallel->world_size()) +
                                      ") covers VAE and translation runs; the CycleGAN baseline trains in one process");
  const RunStart start = args.count("resume")  ? RunStart::resume
                         : args.count("force") ? RunStart::force
                                               : RunStart::fresh;
  if (task == "translation") {
    TranslationTrainOptions train_options;
    train_options.start = start;
    train_options.parallel = parallel;
    if (parallel && !parallel->leader()) train_options.progress = nullptr;
    const TranslationTrainSummary s = train_translation(read_translation_train_config(root), train_options);
    if (parallel && !parallel->leader()) return 0;
    std::cout << fmt::format(
        "{}: {} epochs{} in {}; {} inputs over {} expressions, {} training and {} held-out triplets\n", s.folder,
        s.epochs_done, s.finished ? "" : " (not finished)", format_duration(s.seconds), s.inputs, s.expressions,
        s.train_triplets, s.held_out_triplets);
    auto accuracy = [](double a) { return std::isfinite(a) ? fmt::format("{:.1f}%", 100 * a) : std::string("-"); };
    for (const TranslationStageSummary& stage : s.stages)
      std::cout << fmt::format(
          "  after {} ({} epochs): L_P {:.5g}, L_G {:.5g}, L_T {:.5g}; triplets right {} train, {} "
          "held out; test-subject L_P {:.5g}\n",
          stage.name, stage.epochs, stage.end.paired, stage.end.group, stage.end.triplet,
          accuracy(stage.end.train_accuracy), accuracy(stage.end.held_out_accuracy), stage.end.test_paired);
    std::cout << fmt::format("  checkpoints: {}/checkpoints/{{last,stage<N>}}.pt, metrics: {}/metrics.{{jsonl,csv}}\n",
                             s.folder, s.folder);
    if (s.finished) std::cout << fmt::format("  next: retarget export {} --out DIR\n", s.folder);
    return 0;
  }
  if (task == "cyclegan") return report_cyclegan(root, start);
  const VaeTrainConfig config = read_vae_train_config(root);

  VaeTrainOptions train_options;
  train_options.start = start;
  train_options.parallel = parallel;
  if (parallel && !parallel->leader()) train_options.progress = nullptr;
  const VaeTrainSummary s = train_vae(config, train_options);
  if (parallel && !parallel->leader()) return 0;
  std::cout << fmt::format(
      "{}: {} epochs{} in {}, {} training samples/s; best validation L1 {:.5f} at epoch {}\n"
      "  checkpoints: {}/checkpoints/{{best,last}}.pt, metrics: {}/metrics.{{jsonl,csv}}\n",
      s.folder, s.epochs_done, s.finished ? "" : " (not finished)", format_duration(s.seconds),
      format_rate(s.samples_per_second), s.best_validation, s.best_epoch, s.folder, s.folder);
  if (!s.baselines.empty()) {
    std::string trivial;
    for (const auto& [name, value] : s.baselines)
      trivial += fmt::format("{}{} {:.5f} (x{:.2f})", trivial.empty() ? "" : ", ", name, value,
                             value > 0 ? s.best_validation / value : std::nan(""));
    std::cout << fmt::format("  trivial answers, same loss (best validation L1 as a multiple of theirs): {}\n",
                             trivial);
  }
  for (const std::string& warning : s.warnings) std::cout << "  warning: " << warning << "\n";
  if (s.finished)
    std::cout << fmt::format("  next: retarget eval vae {} ; retarget export {} --out DIR\n", s.folder, s.folder);
  return 0;
}

}  // namespace retarget::cli
