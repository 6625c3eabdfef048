// `retarget rig-map fit --correspondences C [--annotation A] [--prior TABLE] --out MAP.yaml`
// `retarget rig-map apply MAP.yaml --faces DIR --correspondences C --out DIR`
// The rig head (correspond/rig_head.h): human blendshape weights -> the rig's controller weights,
// learnt from the annotated champions, with a controller table as prior.
#include <fmt/format.h>

#include <cmath>
#include <cxxopts.hpp>
#include <iostream>
#include <string>

#include "cli/belief_options.h"
#include "cli/command_options.h"
#include "cli/commands.h"
#include "core/error.h"
#include "correspond/rig_head.h"

namespace retarget::cli {

namespace {

// A number given as text, or an error naming the option.
double number_option(const std::string& option, const std::string& text) {
  size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !std::isfinite(value))
    throw Error(option, fmt::format("expected a number or auto, got \"{}\"", text));
  return value;
}

int fit(int argc, char** argv) {
  cxxopts::Options options("retarget rig-map fit",
                           "Fit the map from human blendshape weights to the avatar's controller weights to an\n"
                           "annotation project's champions (each recipe -> its champion's rig weights), ridge-\n"
                           "regularised towards --prior (a controller table, e.g. `avatar meaning`'s). Without\n"
                           "--annotation the map is the prior alone: the zero-annotation path.");
  RigHeadFitOptions o;
  options.add_options()("correspondences", "the correspondence folder", cxxopts::value<std::string>())(
      "annotation", "an annotation project whose champions teach the map (repeatable, in round order)",
      cxxopts::value<std::vector<std::string>>())("prior", "a controller table the map starts from",
                                                  cxxopts::value<std::string>())(
      "prior-weight", "ridge towards the prior: a number, or auto (chosen by cross-validation on the comparisons)",
      cxxopts::value<std::string>()->default_value("auto"))(
      "champions-only", "fit the champions alone (closed form), not every decided comparison")(
      "belief",
      "the belief search's map: every comparison observed from --prior (its own model of people), then read again "
      "against all the others (--belief-passes)")("out", "the map file to write (YAML)", cxxopts::value<std::string>());
  add_belief_options(options, BeliefSearchOptions::map_reading());
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  if (!args.count("out")) throw Error("retarget rig-map fit", "expected --out MAP.yaml");
  if (args.count("correspondences")) o.correspondences = args["correspondences"].as<std::string>();
  if (args.count("annotation")) o.annotations = args["annotation"].as<std::vector<std::string>>();
  if (args.count("prior")) o.prior = args["prior"].as<std::string>();
  const std::string weight = args["prior-weight"].as<std::string>();
  o.choose_prior_weight = weight == "auto";
  if (!o.choose_prior_weight) o.map.prior_weight = o.ranking.prior_weight = number_option("--prior-weight", weight);
  o.comparisons = args.count("champions-only") == 0;
  o.belief = args.count("belief") > 0;
  o.belief_search = belief_options(args);
  const ControllerMap map = fit_rig_head(o);
  write_controller_map(args["out"].as<std::string>(), map);
  std::cout << fmt::format("controller map {} x {} from {} annotated pairs{}: {}\n", map.controllers.size(),
                           map.shapes.size(), map.pairs, o.prior.empty() ? "" : " and the prior " + o.prior,
                           args["out"].as<std::string>());
  return 0;
}

int apply(int argc, char** argv) {
  cxxopts::Options options("retarget rig-map apply",
                           "Carry the faces written by `retarget faces` onto the rig: each face's blendshape\n"
                           "weights (fitted with the human dataset's face model), through the map, on the rig.\n"
                           "Writes OUT/<face>.obj and OUT/weights.csv, for `retarget eval retarget --method`.");
  options.add_options()("map", "the map file", cxxopts::value<std::string>())(
      "faces", "folder written by `retarget faces`", cxxopts::value<std::string>())(
      "correspondences", "the correspondence folder (its datasets name the face model and the rig)",
      cxxopts::value<std::string>())("out", "output folder", cxxopts::value<std::string>());
  options.parse_positional({"map"});
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  for (const char* key : {"map", "faces", "correspondences", "out"})
    if (!args.count(key)) throw Error("retarget rig-map apply", fmt::format("expected --{} (see --help)", key));
  const RigHeadApplyResult r =
      apply_rig_head(load_controller_map(args["map"].as<std::string>()), args["faces"].as<std::string>(),
                     args["correspondences"].as<std::string>(), args["out"].as<std::string>());
  std::cout << fmt::format("{} faces onto the rig: {}\n", r.faces, r.weights_csv);
  return 0;
}

}  // namespace

int rig_map_command(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "-h" || std::string(argv[1]) == "--help") {
    std::cout << "Usage: retarget rig-map fit --correspondences C [--annotation A] [--prior TABLE] --out MAP.yaml\n"
                 "       retarget rig-map apply MAP.yaml --faces DIR --correspondences C --out DIR\n";
    return argc < 2 ? 1 : 0;
  }
  const std::string what = argv[1];
  if (what == "fit") return fit(argc - 1, argv + 1);
  if (what == "apply") return apply(argc - 1, argv + 1);
  throw Error("retarget rig-map", "unknown subcommand '" + what + "' (known: fit, apply)");
}

}  // namespace retarget::cli
