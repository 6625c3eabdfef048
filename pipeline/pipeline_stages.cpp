#include "pipeline/pipeline_stages.h"

#include <algorithm>
#include <filesystem>

#include "core/config_base.h"
#include "train/run_folder.h"

namespace fs = std::filesystem;

namespace retarget {

std::string StageCommand::text() const {
  std::string text = program;
  for (const std::string& a : args)
    text += " " + (a.empty() || a.find_first_of(" \t\"'$;&|<>*?()[]{}") != std::string::npos ? "'" + a + "'" : a);
  return text;
}

StageCommand retarget_command(std::vector<std::string> args) { return {"retarget", std::move(args)}; }
StageCommand infer_command_line(std::vector<std::string> args) { return {"retarget-infer", std::move(args)}; }

namespace {

// Adds `key` to the stage's upstream stages, once.
void run_after(Stage& stage, const std::string& key) {
  if (std::find(stage.after.begin(), stage.after.end(), key) == stage.after.end()) stage.after.push_back(key);
}

}  // namespace

void depend_on_rig(const Recipe& recipe, const RunLayout& layout, Stage& stage) {
  if (recipe.avatar.init) {
    run_after(stage, "avatar");
  } else if (recipe.avatar.synthetic()) {
    run_after(stage, "synth");
  } else {
    stage.inputs.push_back(layout.rig_source);
  }
}

void depend_on_face_model(const Recipe& recipe, const RunLayout& layout, Stage& stage) {
  if (recipe.human.synthetic()) {
    run_after(stage, "synth");
  } else {
    stage.inputs.push_back(layout.face_model);
  }
}

void depend_on_table(const Recipe& recipe, const RunLayout& layout, Stage& stage) {
  if (recipe.avatar.synthetic() && recipe.avatar.table.empty()) {
    run_after(stage, "synth");
  } else {
    stage.inputs.push_back(layout.table);
  }
}

Stage training_stage(const std::string& key, const std::string& title, const std::string& config,
                     const std::vector<std::string>& sets, const std::string& folder,
                     const std::vector<StageCommand>& then, int processes) {
  const std::vector<std::string> nproc =
      processes > 1 ? std::vector<std::string>{"--nproc", std::to_string(processes)} : std::vector<std::string>{};
  Stage s;
  s.key = key;
  s.family = "train";
  s.title = title;
  std::vector<std::string> args{"train", config};
  for (const std::string& set : sets) args.insert(args.end(), {"--set", set});
  args.insert(args.end(), {"--out", folder, "--force"});
  args.insert(args.end(), nproc.begin(), nproc.end());
  s.commands.push_back(retarget_command(args));
  s.commands.insert(s.commands.end(), then.begin(), then.end());
  s.inputs = config_chain_files(config);  // a change to a profile's base reruns the runs built on it
  s.resume = [folder, then, nproc]() -> std::optional<std::vector<StageCommand>> {
    if (!fs::exists(fs::path(folder) / "run.yaml")) return std::nullopt;  // killed before the run began: start over
    std::vector<StageCommand> commands;
    if (RunStatus::load(folder).status != "finished") {
      std::vector<std::string> resume{"train", folder, "--resume"};
      resume.insert(resume.end(), nproc.begin(), nproc.end());
      commands.push_back(retarget_command(resume));
    }
    commands.insert(commands.end(), then.begin(), then.end());
    return commands;
  };
  return s;
}

std::vector<Stage> pipeline_stages(const Recipe& recipe, const std::string& run) {
  const RunLayout layout = run_layout(recipe, run);
  std::vector<Stage> stages;
  add_data_stages(recipe, layout, stages);
  add_method_stages(recipe, layout, stages);
  return stages;
}

}  // namespace retarget
