// `retarget pipeline RECIPE --out RUN [--set k=v]... [--from STAGE] [--until STAGE] [--force]`:
// the whole method from one recipe (pipeline/recipe.h), stage by stage, skipping what is up to
// date and resuming what a kill interrupted (pipeline/pipeline_runner.h). Each stage's commands
// run in this process: `retarget` subcommands through cli::run, inference through retarget-infer's
// own function.
#include <fmt/format.h>
#include <torch/torch.h>

#include <cxxopts.hpp>
#include <filesystem>
#include <iostream>

#include "cli/cli.h"
#include "cli/command_options.h"
#include "cli/commands.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "infer/infer_command.h"
#include "pipeline/evaluation_summary.h"
#include "pipeline/pipeline_runner.h"
#include "pipeline/pipeline_stages.h"

namespace retarget::cli {

namespace fs = std::filesystem;

namespace {

// What a fresh process starts with, which every command gets again: commands run here one after
// another, and one that sets LibTorch's thread count (a training) or draws from its global
// generator would otherwise change the sums and draws of the next (the pipeline gives the
// results the commands give run one by one, to the seeded digit).
struct ProcessStart {
  int threads = torch::get_num_threads();
  void restore() const {
    torch::set_num_threads(threads);
    torch::manual_seed(c10::default_rng_seed_val);
  }
};

int run_stage_command(const StageCommand& command) {
  static const ProcessStart start;
  start.restore();
  std::vector<std::string> args = command.args;
  args.insert(args.begin(), command.program);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const int argc = static_cast<int>(args.size());
  if (command.program == "retarget") return run(argc, argv.data());
  if (command.program == "retarget-infer") return infer_command(argc, argv.data());
  throw Error("pipeline", "no program \"" + command.program + "\"");
}

}  // namespace

int pipeline_command(int argc, char** argv) {
  const std::vector<std::string> overrides = take_overrides("retarget pipeline", argc, argv);
  cxxopts::Options options(
      "retarget pipeline",
      "The whole method from one recipe: the data, the VAEs, rounds of comparisons (simulated annotators or\n"
      "people in the web tool), the translation network, bundles, the rig head, inference on unseen people's\n"
      "faces, the evaluation and the error ladder. Each stage records a manifest in RUN/pipeline/; a rerun\n"
      "skips what is up to date and resumes what was interrupted (a training from its last checkpoint).\n"
      "  retarget pipeline configs/recipes/demo.yaml --out out/demo\n"
      "  retarget pipeline configs/recipes/demo.yaml --out out/demo --set method.budget=700 --set method.folder=b700\n"
      "  retarget pipeline configs/recipes/real.yaml --out out/real --from method/translation");
  options.add_options()("recipe", "the recipe YAML (configs/recipes/)", cxxopts::value<std::string>())(
      "out", "the run folder", cxxopts::value<std::string>())(
      "set", "override a recipe value with YAML, e.g. --set method.budget=700 (repeatable)")(
      "from", "rerun this stage (a key, a key's folder or a family: round, train...) and every later one",
      cxxopts::value<std::string>())("until", "stop after the last stage this names", cxxopts::value<std::string>())(
      "force", "run every stage, up to date or not")("dry-run", "print the stages and what a run would do");
  options.parse_positional({"recipe"});
  options.positional_help("RECIPE --out RUN");
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  if (!args.count("recipe")) throw Error("retarget pipeline", "expected a recipe (see --help)");
  if (!args.count("out")) throw Error("retarget pipeline", "expected --out RUN, the run folder");
  const Recipe recipe = load_recipe(args["recipe"].as<std::string>(), overrides);
  PipelineRunOptions run;
  run.run = fs::absolute(args["out"].as<std::string>()).lexically_normal().string();
  if (args.count("from")) run.from = args["from"].as<std::string>();
  if (args.count("until")) run.until = args["until"].as<std::string>();
  run.force = args.count("force") > 0;
  run.dry_run = args.count("dry-run") > 0;
  const std::vector<Stage> stages = pipeline_stages(recipe, run.run);
  if (!run.dry_run) {
    fs::create_directories(run.run);
    write_file_atomically((fs::path(run.run) / "recipe.yaml").string(), [&](std::ostream& out) { out << recipe.text; });
  }
  run_pipeline(stages, run, run_stage_command);
  if (run.dry_run) return 0;
  const std::string metrics = (fs::path(run.run) / recipe.method.folder / "evaluation" / "metrics.json").string();
  const std::string summary = evaluation_summary(metrics);
  if (!summary.empty()) {
    std::cout << summary;
    write_file_atomically((fs::path(run.run) / "summary.txt").string(), [&](std::ostream& out) { out << summary; });
  }
  return 0;
}

}  // namespace retarget::cli
