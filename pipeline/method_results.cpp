// The method's stages after the rounds (pipeline/pipeline_stages.h: add_method_results).
#include <fmt/format.h>

#include <filesystem>
#include <string>

#include "pipeline/pipeline_stages.h"

namespace fs = std::filesystem;

namespace retarget {

namespace {

Stage result_stage(const std::string& prefix, const std::string& name, const std::string& title,
                   std::vector<StageCommand> commands, std::vector<std::string> after) {
  Stage s;
  s.key = prefix + name;
  s.family = name;
  s.title = title;
  s.commands = std::move(commands);
  s.after = std::move(after);
  return s;
}

}  // namespace

void add_method_results(const Recipe& recipe, const RunLayout& l, const std::string& prefix,
                        const std::vector<std::string>& projects, int last_round, std::vector<Stage>& stages) {
  const std::string method = l.method;
  const std::string last_project = projects.back();
  const std::string last_corr = path_in(l.round(last_round), "correspondences");
  const std::string round_key = prefix + fmt::format("round-{:02d}", last_round);
  std::vector<std::string> every_round;
  for (int r = 1; r <= last_round; ++r) every_round.push_back(prefix + fmt::format("round-{:02d}", r));

  // F on the last round's groups and triplets.
  const std::string translation = path_in(method, "translation");
  std::vector<std::string> sets{"data.human_vae=" + l.human_vae, "data.avatar_vae=" + l.avatar_vae,
                                "data.correspondences=" + last_corr, "data.triplets=" + last_project};
  if (auto it = recipe.training.find("translation"); it != recipe.training.end())
    sets.insert(sets.end(), it->second.begin(), it->second.end());
  Stage f = training_stage(
      prefix + "translation", fmt::format("the translation network on round {}'s groups and triplets", last_round),
      path_in(recipe.profile, "translation.yaml"), sets, translation, {}, recipe.training_processes);
  f.commands.insert(f.commands.begin(), retarget_command({"annotate", "export", last_project, "--out",
                                                          path_in(last_project, "triplets.csv")}));
  f.after = {round_key, "runs/avatar_vae", "runs/human_vae"};
  stages.push_back(std::move(f));

  const std::string bundle = path_in(method, "bundle"), stage1 = path_in(method, "bundle-stage1"),
                    lec = path_in(method, "bundle-lec");
  stages.push_back(result_stage(prefix, "bundle",
                                "the retargeting bundles (full, stage 1 alone, and linear expression cloning)",
                                {retarget_command({"export", translation, "--out", bundle}),
                                 retarget_command({"export", translation, "--checkpoint", "stage1", "--out", stage1}),
                                 retarget_command({"export", translation, "--lec", "--out", lec})},
                                {prefix + "translation"}));

  // The rig head on every round's answers, and the proposed table alone (no person).
  std::vector<std::string> head{"rig-map", "fit", "--correspondences", path_in(l.round(1), "correspondences")};
  for (const std::string& p : projects) head.insert(head.end(), {"--annotation", p});
  head.insert(head.end(), {"--prior", l.proposed});
  if (recipe.method.search == "belief") head.push_back("--belief");  // the belief's most likely map
  head.insert(head.end(), {"--out", path_in(method, "rig_head.yaml")});
  std::vector<std::string> after_rounds = every_round;
  after_rounds.push_back("proposed");
  stages.push_back(
      result_stage(prefix, "rig-head", "the rig head on every round's answers, and the proposed table alone",
                   {retarget_command(head),
                    retarget_command({"rig-map", "fit", "--correspondences", path_in(l.round(1), "correspondences"),
                                      "--prior", l.proposed, "--out", path_in(method, "zero_annotation.yaml")})},
                   after_rounds));

  // Every method on the test faces, the rig head through the runtime as users run it.
  std::vector<StageCommand> infer{
      infer_command_line({"--bundle", bundle, l.test_faces, "--out", path_in(method, "full")}),
      infer_command_line({"--bundle", stage1, l.test_faces, "--out", path_in(method, "stage1")}),
      infer_command_line({"--bundle", lec, l.test_faces, "--out", path_in(method, "lec")}),
      infer_command_line({"--bundle", l.cyclegan_bundle(), l.test_faces, "--out", path_in(method, "cyclegan")})};
  for (const char* map : {"rig_head", "zero_annotation"})
    infer.push_back(infer_command_line({"--bundle", bundle, "--rig-map", path_in(method, std::string(map) + ".yaml"),
                                        "--face-model", l.face_model, l.test_faces, "--out", path_in(method, map)}));
  stages.push_back(result_stage(prefix, "inference", "every method on the test faces", infer,
                                {prefix + "bundle", "runs/cyclegan", prefix + "rig-head", "test_faces"}));

  Stage eval =
      result_stage(prefix, "evaluation", "the evaluation per set (references, blends) beside the trivial answers",
                   {retarget_command({"eval",
                                      "retarget",
                                      "--faces",
                                      l.test_faces,
                                      "--correspondences",
                                      last_corr,
                                      "--table",
                                      l.table,
                                      "--method",
                                      "lec=" + path_in(method, "lec"),
                                      "--method",
                                      "cyclegan=" + path_in(method, "cyclegan"),
                                      "--method",
                                      "stage1=" + path_in(method, "stage1"),
                                      "--method",
                                      "full=" + path_in(method, "full"),
                                      "--method",
                                      "zero_annotation=" + path_in(method, "zero_annotation"),
                                      "--method",
                                      "rig_head=" + path_in(method, "rig_head"),
                                      "--out",
                                      path_in(method, "evaluation")})},
                   {prefix + "inference", round_key});
  depend_on_table(recipe, l, eval);
  stages.push_back(std::move(eval));

  Stage ladder = result_stage(
      prefix, "ladder", "the error ladder: where the error enters, stage by stage",
      {retarget_command({"eval", "ladder", "--correspondences", last_corr, "--translation", translation, "--table",
                         l.table, "--faces", l.test_faces, "--out", path_in(path_in(method, "evaluation"), "ladder")})},
      {prefix + "evaluation", prefix + "translation"});
  depend_on_table(recipe, l, ladder);
  stages.push_back(std::move(ladder));

  stages.push_back(result_stage(
      prefix, "plots", "pictures: the trainings' curves, the errors per method, region and expression",
      {retarget_command({"plot", l.avatar_vae, l.human_vae, translation, l.cyclegan, path_in(method, "evaluation")})},
      {"runs/avatar_vae", "runs/human_vae", prefix + "translation", "runs/cyclegan", prefix + "evaluation"}));
}

}  // namespace retarget
