// retarget correspond: a human dataset, an avatar dataset and its VAE run -> a correspondence
// folder (correspond/correspondence.h).
#include <fmt/format.h>

#include <cxxopts.hpp>
#include <iostream>
#include <sstream>

#include "cli/belief_options.h"
#include "cli/command_options.h"
#include "cli/commands.h"
#include "core/error.h"
#include "correspond/correspondence.h"
#include "pipeline/round_starts.h"

namespace retarget::cli {

namespace {

std::vector<std::string> split_commas(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream stream(text);
  for (std::string item; std::getline(stream, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

}  // namespace

int correspond_command(int argc, char** argv) {
  cxxopts::Options options("retarget correspond",
                           "Geometric correspondences (correspond/correspondence.h): each human reference expression\n"
                           "(identity-averaged) is carried onto the avatar by deformation transfer; its avatar code\n"
                           "y0 and the P nearest avatar dataset samples (its group) are written to --out.");
  CorrespondenceOptions o;
  options.add_options()("human", "the human dataset folder", cxxopts::value<std::string>())(
      "avatar", "the avatar dataset folder", cxxopts::value<std::string>())(
      "avatar-vae", "the avatar VAE run folder (trained on that avatar dataset)", cxxopts::value<std::string>())(
      "out", "the correspondence folder to write", cxxopts::value<std::string>())(
      "group-size", "P: avatar samples per group", cxxopts::value<int>()->default_value(std::to_string(o.group_size)))(
      "expressions", "human expressions to use, comma-separated (default: all)", cxxopts::value<std::string>())(
      "landmarks", "landmark pairs file (human = source, avatar = target; default: the landmark names both share)",
      cxxopts::value<std::string>())("checkpoint", "of the avatar VAE run: best or last",
                                     cxxopts::value<std::string>()->default_value(o.checkpoint))(
      "initial",
      "what y0 and the groups start from: rig (DT projected onto the rig), dt (raw DT, the paper) or champions "
      "(of --around)",
      cxxopts::value<std::string>()->default_value(o.initial))(
      "spread", "members of each group chosen for variety instead of nearness (0 to group size - 1)",
      cxxopts::value<int>()->default_value(std::to_string(o.spread)))(
      "around",
      "an annotation project over earlier correspondences: start each expression from its tournament's champion "
      "(implies --initial champions)",
      cxxopts::value<std::string>())(
      "start-table",
      "a controller table (e.g. `avatar meaning`'s): start each expression from the rig at the weights it gives the "
      "recipe (implies --initial table)",
      cxxopts::value<std::string>())(
      "proposals",
      "members of each group generated from the rig around the start (the start itself first) instead of taken "
      "from the dataset; needs --initial rig, champions or table",
      cxxopts::value<int>()->default_value(std::to_string(o.proposals.count)))(
      "proposal-sigma", "step of each proposal, a fraction of each moved controller's range",
      cxxopts::value<double>()->default_value(fmt::format("{}", o.proposals.sigma)))(
      "proposal-controllers", "controllers each proposal moves",
      cxxopts::value<int>()->default_value(std::to_string(o.proposals.controllers)))(
      "proposal-seed", "seed of the proposals",
      cxxopts::value<uint64_t>()->default_value(std::to_string(o.proposals.seed)))(
      "informative",
      "the belief search: each group is the pair of rig expressions with the most expected information under the "
      "map belief from --start-table after the rounds of --evidence (groups of 2)")(
      "evidence", "an earlier round's annotation project the belief observes (repeatable, in round order)",
      cxxopts::value<std::vector<std::string>>())("force", "replace the correspondences in a folder that is not empty");
  add_belief_options(options);
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  for (const char* required : {"human", "avatar", "avatar-vae", "out"})
    if (!args.count(required)) throw Error(std::string("missing --") + required + " (see --help)");
  o.group_size = args["group-size"].as<int>();
  if (args.count("expressions")) {
    o.expressions = split_commas(args["expressions"].as<std::string>());
    if (o.expressions.empty()) throw Error("--expressions", "name at least one expression");
  }
  if (args.count("landmarks")) o.landmarks_file = args["landmarks"].as<std::string>();
  o.checkpoint = args["checkpoint"].as<std::string>();
  o.initial = args["initial"].as<std::string>();
  o.spread = args["spread"].as<int>();
  o.proposals.count = args["proposals"].as<int>();
  o.proposals.sigma = args["proposal-sigma"].as<double>();
  o.proposals.controllers = args["proposal-controllers"].as<int>();
  o.proposals.seed = args["proposal-seed"].as<uint64_t>();
  if (args.count("around")) {
    o.around = args["around"].as<std::string>();
    if (args["initial"].count() == 0) o.initial = "champions";
  }
  if (args.count("start-table")) {
    o.start_table = args["start-table"].as<std::string>();
    if (args["initial"].count() == 0) o.initial = "table";
  }
  o.informative = args.count("informative") > 0;
  if (args.count("evidence")) o.evidence = args["evidence"].as<std::vector<std::string>>();
  if (o.informative && args["group-size"].count() == 0) o.group_size = 2;
  // The rounds before decide this one's starts (pipeline/round_starts.h).
  if (!o.around.empty()) o.round_starts = champions_of(o.around);
  if (args["belief-passes"].as<int>() != 0)
    throw Error("--belief-passes",
                "only `retarget rig-map fit` refines the belief; a round's search reads each answer once");
  if (args["belief-annotator-sd"].as<double>() != 0)
    throw Error("--belief-annotator-sd",
                "only `retarget rig-map fit` reads the map the annotators share; a round's search pools the answers");
  if (args["belief-leave-one-out"].as<bool>())
    throw Error("--belief-leave-one-out",
                "only `retarget rig-map fit` reads the map without each annotator; a round's search pools the answers");
  if (args["belief-jackknife"].as<double>() != 0)
    throw Error("--belief-jackknife",
                "only `retarget rig-map fit` reads the map without each annotator; a round's search pools the answers");
  if (!args["belief-jackknife-also"].as<std::string>().empty())
    throw Error("--belief-jackknife-also",
                "only `retarget rig-map fit` reads the map without each annotator; a round's search pools the answers");
  if (o.informative && !o.start_table.empty())
    o.round_starts = belief_search_round(o.start_table, o.evidence, belief_options(args));
  o.force = args.count("force") > 0;

  CorrespondenceReport r;
  const std::string out = args["out"].as<std::string>();
  const Correspondences c = build_correspondences(args["human"].as<std::string>(), args["avatar"].as<std::string>(),
                                                  args["avatar-vae"].as<std::string>(), out, o, &r);
  const int64_t dataset_members = c.group_size - c.spread - c.proposals.count;
  const torch::Tensor nearest = c.distances.select(1, 0),
                      farthest = c.distances.select(1, std::max<int64_t>(dataset_members - 1, 0));
  std::cout << fmt::format("correspondences {}: {} groups of {} samples of the avatar {} ({}), codes of size {}\n", out,
                           c.expression_count(), c.group_size, c.avatar_name, c.avatar_dataset, c.y0.size(1));
  std::cout << fmt::format(
      "  deformation transfer: {} landmark pairs, fit to the avatar surface mean {:.4g} / max {:.4g} avatar units, "
      "{} triangle pairs ({} fallback, {} held to identity)\n",
      r.landmark_pairs, r.transfer.mean_distance, r.transfer.max_distance, r.transfer.triangle_pairs,
      r.transfer.fallback_target_triangles, r.transfer.identity_target_triangles);
  std::cout << fmt::format(
      "  initial avatar expressions: {}\n"
      "  raw-DR distance of the groups to their initial expression: nearest mean {:.4g}, farthest near member mean "
      "{:.4g}; {} member{} per group chosen for variety, {} proposed by the rig\n",
      c.initial == "rig"         ? "the DT results projected onto the rig (dt_rig/)"
      : c.initial == "champions" ? "the tournament champions of " + c.around
      : c.initial == "table"     ? "the rig at the weights of the table " + c.start_table
                                 : std::string("the raw DT results (dt/)"),
      nearest.mean().item<double>(), farthest.mean().item<double>(), c.spread, c.spread == 1 ? "" : "s",
      c.proposals.count);
  std::cout << fmt::format(
      "  {:.2f} s: inputs {:.2f}, references {:.2f}, transfer and DR {:.2f}, search {:.2f}, encoding {:.2f}, writing "
      "{:.2f}\n",
      r.seconds, r.load_seconds, r.reconstruction_seconds, r.transfer_seconds, r.search_seconds, r.encode_seconds,
      r.write_seconds);
  return 0;
}

}  // namespace retarget::cli
