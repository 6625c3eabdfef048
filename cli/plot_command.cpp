// `retarget plot FOLDER... [--out DIR]`: pictures of training runs and evaluations (plot/run_plots.h).
#include <fmt/format.h>

#include <cxxopts.hpp>
#include <iostream>

#include "cli/command_options.h"
#include "cli/commands.h"
#include "core/error.h"
#include "plot/run_plots.h"

namespace retarget::cli {

int plot_command(int argc, char** argv) {
  cxxopts::Options options(
      "retarget plot",
      "Pictures, drawn by gnuplot, of what a folder holds, into FOLDER/plots/ (with the data and the gnuplot\n"
      "script of each, to rerun or adapt):\n"
      "  a training run (metrics.csv): training.png, the losses per epoch (a VAE's validation L1 beside the\n"
      "    neutral and mean answers'; the translation network's L_P, L_G, L_T and triplet accuracies);\n"
      "  an evaluation (`retarget eval retarget`, metrics.json): methods.png (each method as a multiple of\n"
      "    the neutral answer, mm and rig weights, per set), regions.png, expressions.png (worst first).\n"
      "  retarget plot out/demo/runs/avatar_vae out/demo/method/translation out/demo/method/evaluation");
  PlotOptions o;
  options.add_options()("folders", "training runs or evaluations", cxxopts::value<std::vector<std::string>>())(
      "out", "the pictures' folder (one FOLDER only; default FOLDER/plots)", cxxopts::value<std::string>())(
      "width", "pixels", cxxopts::value<int>()->default_value(std::to_string(o.width)))(
      "height", "pixels", cxxopts::value<int>()->default_value(std::to_string(o.height)));
  options.parse_positional({"folders"});
  options.positional_help("FOLDER...");
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  if (!args.count("folders")) throw Error("retarget plot", "expected a training run or an evaluation folder");
  const std::vector<std::string> folders = args["folders"].as<std::vector<std::string>>();
  if (args.count("out") && folders.size() > 1) throw Error("--out", "names the pictures' folder of one FOLDER only");
  o.width = args["width"].as<int>();
  o.height = args["height"].as<int>();
  for (const std::string& folder : folders) {
    o.folder = folder;
    if (args.count("out")) o.out = args["out"].as<std::string>();
    for (const std::string& png : write_plots(o)) std::cout << "  written: " << png << "\n";
  }
  return 0;
}

}  // namespace retarget::cli
