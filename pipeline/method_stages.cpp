// The method on its budget (pipeline/pipeline_stages.h, after the data stages): the annotation
// dataset, the rounds of comparisons (pipeline/rounds_plan.h) answered by simulated annotators
// or by people in the web tool, the translation network on the last round, its bundles, the rig
// head and the zero-annotation map, every method on the test faces, the evaluation and the ladder.
#include <fmt/format.h>

#include <filesystem>
#include <string>

#include "geometry/face_model.h"
#include "pipeline/input_digests.h"
#include "pipeline/pipeline_stages.h"
#include "pipeline/round_answers.h"
#include "pipeline/rounds_plan.h"

namespace fs = std::filesystem;

namespace retarget {

namespace {

struct MethodContext {
  const Recipe& recipe;
  const RunLayout& l;
  std::string prefix;  // the method folder as a key prefix: "method/"
  std::string annotation_dataset;
  std::vector<std::string> projects;  // the rounds' annotation projects so far
};

Stage method_stage(const MethodContext& m, const std::string& name, const std::string& family,
                   const std::string& title) {
  Stage s;
  s.key = m.prefix + name;
  s.family = family;
  s.title = title;
  return s;
}

std::string round_key(const MethodContext& m, int number) { return m.prefix + fmt::format("round-{:02d}", number); }

// How round r's candidates are proposed: `retarget correspond` (and, for map search, the rig head
// of the rounds before as its start).
std::vector<StageCommand> propose_round(const MethodContext& m, const RoundPlan& r) {
  const RunLayout& l = m.l;
  const std::string corr = path_in(l.round(r.number), "correspondences");
  const std::string search = m.recipe.method.search;
  std::vector<std::string> args{"correspond", "--human",        r.blends ? m.annotation_dataset : l.human_dataset,
                                "--avatar",   l.avatar_dataset, "--avatar-vae",
                                l.avatar_vae};
  std::vector<StageCommand> commands;
  const std::string size = std::to_string(r.group_size);
  if (search == "belief") {
    args.insert(args.end(), {"--start-table", l.proposed, "--informative"});
    for (const std::string& p : m.projects) args.insert(args.end(), {"--evidence", p});
  } else if (r.number == 1) {
    // From the proposed table: the start itself, rig proposals around it and, in full groups,
    // dataset samples chosen for variety.
    const bool full = r.group_size >= 16;
    args.insert(args.end(), {"--start-table", l.proposed, "--group-size", size, "--spread", full ? "8" : "0",
                             "--proposals", std::to_string(full ? 4 : r.group_size - 1), "--proposal-seed", "1"});
  } else if (search == "champions") {
    args.insert(args.end(), {"--around", m.projects.back(), "--group-size", size, "--proposals", size,
                             "--proposal-seed", std::to_string(r.number)});
  } else {
    const std::string start = path_in(l.round(r.number), "start_map.yaml");
    std::vector<std::string> fit{"rig-map", "fit", "--correspondences", path_in(l.round(1), "correspondences")};
    for (const std::string& p : m.projects) fit.insert(fit.end(), {"--annotation", p});
    fit.insert(fit.end(), {"--prior", l.proposed, "--out", start});
    commands.push_back(retarget_command(fit));
    args.insert(args.end(),
                {"--start-table", start, "--group-size", size, "--proposals", size, "--proposal-sigma",
                 fmt::format("{:.3f}", map_search_step(r.number)), "--proposal-seed", std::to_string(r.number)});
  }
  args.insert(args.end(), {"--out", corr, "--force"});
  commands.push_back(retarget_command(args));
  return commands;
}

Stage round_stage(MethodContext& m, const RoundPlan& r, int rounds) {
  const RunLayout& l = m.l;
  const std::string project = path_in(l.round(r.number), "annotation");
  const bool belief = m.recipe.method.search == "belief";
  const std::string what = belief ? (r.blends ? "one informative pair per reference and training blend"
                                              : "one informative pair per reference")
                                  : fmt::format("groups of {} proposed by the rig", r.group_size);
  Stage s =
      method_stage(m, fmt::format("round-{:02d}", r.number), "round",
                   fmt::format("round {} of {}: {} ({} comparisons, {})", r.number, rounds, what, r.cost,
                               m.recipe.annotators.kind == "people" ? "answered by people" : "simulated annotators"));
  s.quiet = belief;
  s.commands = propose_round(m, r);
  // Each round queues its groups in its own order (queue_order): no expression is one person's.
  s.commands.push_back(
      retarget_command({"annotate", "init", "--correspondences", path_in(l.round(r.number), "correspondences"), "--out",
                        project, "--seed", std::to_string(r.number), "--force"}));
  if (m.recipe.annotators.kind == "simulated") {
    std::vector<std::string> simulate{
        "annotate", "simulate", project, "--table", l.table, "--seed", std::to_string(r.number)};
    for (const auto& [name, value] : m.recipe.annotators.simulate) {
      if (name == "oracle") {
        if (value == "true") simulate.push_back("--oracle");
      } else {
        simulate.insert(simulate.end(), {"--" + name, value});
      }
    }
    s.commands.push_back(retarget_command(simulate));
    depend_on_table(m.recipe, l, s);
  } else {
    const double poll = m.recipe.annotators.poll_seconds;
    s.wait = [project, poll]() { wait_for_round_answers(project, poll); };
    // Interrupted while people answered: keep their answers and wait again (never init anew).
    s.resume = [project]() -> std::optional<std::vector<StageCommand>> {
      if (!fs::exists(path_in(project, "annotations.db"))) return std::nullopt;
      return std::vector<StageCommand>{};
    };
  }
  s.after.insert(s.after.end(), {"datasets/avatar", "datasets/human", "runs/avatar_vae", "proposed"});
  if (r.blends) s.after.push_back(m.prefix + "annotation-dataset");
  for (int previous = 1; previous < r.number; ++previous) s.after.push_back(round_key(m, previous));
  m.projects.push_back(project);
  return s;
}

}  // namespace

void add_method_stages(const Recipe& recipe, const RunLayout& l, std::vector<Stage>& stages) {
  MethodContext m{recipe, l, recipe.method.folder + "/", path_in(l.method, "annotation_dataset"), {}};
  const RecipeMethod& method = recipe.method;
  const int groups = static_cast<int>(load_expression_recipes(recipe.human.recipes).size());
  const bool blends = method.search == "belief" && method.annotation_blends > 0;
  const std::vector<RoundPlan> rounds =
      plan_rounds(method.budget, method.search, groups, blends ? groups + method.annotation_blends : groups);
  if (blends) {
    Stage s =
        method_stage(m, "annotation-dataset", "dataset",
                     fmt::format("the expressions rounds ask about: the {} references and {} random training blends",
                                 groups, method.annotation_blends));
    s.quiet = true;
    s.commands.push_back(retarget_command({"dataset", "--face-model", l.face_model, "--recipes", recipe.human.recipes,
                                           "--blends", std::to_string(method.annotation_blends), "--people",
                                           std::to_string(method.annotation_people), "--no-preview", "--out",
                                           m.annotation_dataset, "--force"}));
    depend_on_face_model(recipe, l, s);
    s.inputs.push_back(recipe.human.recipes);
    stages.push_back(std::move(s));
  }
  for (const RoundPlan& r : rounds) stages.push_back(round_stage(m, r, static_cast<int>(rounds.size())));
  const int last = static_cast<int>(rounds.size());
  add_method_results(recipe, l, m.prefix, m.projects, last, stages);
}

}  // namespace retarget
