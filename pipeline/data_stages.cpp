// The stages before the method (pipeline/pipeline_stages.h): synthetic data, avatar init, the
// two datasets, pictures and the geometry demo, the VAEs, the proposed table and the test faces.
#include <algorithm>
#include <filesystem>
#include <string>

#include "pipeline/pipeline_stages.h"

namespace fs = std::filesystem;

namespace retarget {

namespace {

Stage stage(const std::string& key, const std::string& family, const std::string& title,
            std::vector<StageCommand> commands) {
  Stage s;
  s.key = key;
  s.family = family;
  s.title = title;
  s.commands = std::move(commands);
  return s;
}

// Up to `count` of a rig folder's target meshes (its .obj files but the neutral), sorted.
std::vector<std::string> rig_targets(const std::string& rig, size_t count) {
  std::vector<std::string> targets;
  if (!fs::is_directory(rig)) return targets;
  for (const auto& entry : fs::directory_iterator(rig))
    if (entry.path().extension() == ".obj" && entry.path().filename() != "neutral.obj")
      targets.push_back(entry.path().string());
  std::sort(targets.begin(), targets.end());
  if (targets.size() > count) targets.resize(count);
  return targets;
}

// RUN/pictures: the synthetic human's blendshapes and the avatar's first controllers.
Stage pictures_stage(const Recipe& recipe, const RunLayout& l) {
  const std::string pictures = path_in(l.run, "pictures");
  Stage s = stage("pictures", "pictures", "pictures of the human's blendshapes and the avatar's controllers",
                  {retarget_command({"render", "(the rig's neutral and first 7 targets)", "--out",
                                     path_in(pictures, "avatar.png")})});
  const bool synthetic_human = recipe.human.synthetic();
  if (synthetic_human)
    s.commands.push_back(
        retarget_command({"render", "(5 blendshapes)", "--out", path_in(pictures, "human_blendshapes.png")}));
  depend_on_rig(recipe, l, s);
  if (synthetic_human) depend_on_face_model(recipe, l, s);
  s.expand = [l, pictures, synthetic_human]() {
    fs::create_directories(pictures);
    std::vector<std::string> avatar{"render", path_in(l.rig_source, "neutral.obj")};
    for (const std::string& t : rig_targets(l.rig_source, 7)) avatar.push_back(t);
    avatar.insert(avatar.end(), {"--title", "avatar " + fs::path(l.rig_source).filename().string() + ": controllers",
                                 "--out", path_in(pictures, "avatar.png")});
    std::vector<StageCommand> commands;
    if (fs::exists(path_in(l.rig_source, "neutral.obj")))  // a rig folder (a glTF rig has no mesh files to draw)
      commands.push_back(retarget_command(avatar));
    if (synthetic_human) {
      const std::string human = path_in(l.synth, "human");
      std::vector<std::string> args{"render", path_in(human, "neutral.obj")};
      for (const char* e : {"jawOpen", "mouthSmile_L", "eyeBlink_L", "browInnerUp_L", "mouthPucker"})
        args.push_back(path_in(path_in(human, "expressions"), std::string(e) + ".obj"));
      args.insert(args.end(),
                  {"--title", "synthetic human: blendshapes", "--out", path_in(pictures, "human_blendshapes.png")});
      commands.push_back(retarget_command(args));
    }
    return commands;
  };
  return s;
}

void add_vae_stage(const Recipe& recipe, const std::string& name, const std::string& dataset_key,
                   const std::string& dataset, const std::string& folder, std::vector<Stage>& stages) {
  std::vector<std::string> sets{"data.dataset=" + dataset};
  auto it = recipe.training.find(name);
  if (it != recipe.training.end()) sets.insert(sets.end(), it->second.begin(), it->second.end());
  Stage s = training_stage("runs/" + name,
                           "the " + name + " (" + fs::path(recipe.profile).filename().string() +
                               " profile), its evaluation in mm and TorchScript export",
                           path_in(recipe.profile, name + ".yaml"), sets, folder,
                           {retarget_command({"eval", "vae", folder}),
                            retarget_command({"export", folder, "--out", path_in(folder, "export")})},
                           recipe.training_processes);
  s.after.push_back(dataset_key);
  stages.push_back(std::move(s));
}

}  // namespace

void add_data_stages(const Recipe& recipe, const RunLayout& l, std::vector<Stage>& stages) {
  if (recipe.human.synthetic() || recipe.avatar.synthetic())
    stages.push_back(stage("synth", "synth", "the synthetic face model and avatar rigs",
                           {retarget_command({"synth", "--out", l.synth, "--force"})}));
  if (recipe.avatar.init) {
    Stage s = stage("avatar", "avatar", "the rig's landmarks, eyes and parts proposed from the rig alone",
                    {retarget_command({"avatar", "init", l.rig_source, "--out", l.rig, "--force"})});
    if (recipe.avatar.synthetic())
      s.after.push_back("synth");
    else
      s.inputs.push_back(l.rig_source);
    stages.push_back(std::move(s));
  }
  std::vector<std::string> avatar_args{"dataset", "--rig", l.rig};
  if (recipe.avatar.samples > 0)
    avatar_args.insert(avatar_args.end(), {"--samples", std::to_string(recipe.avatar.samples)});
  avatar_args.insert(avatar_args.end(), {"--out", l.avatar_dataset, "--force"});
  Stage avatar =
      stage("datasets/avatar", "dataset", "the avatar's dataset of rig expressions", {retarget_command(avatar_args)});
  depend_on_rig(recipe, l, avatar);
  stages.push_back(std::move(avatar));

  std::vector<std::string> human_args{"dataset", "--face-model", l.face_model, "--recipes", recipe.human.recipes};
  if (recipe.human.people > 0) human_args.insert(human_args.end(), {"--people", std::to_string(recipe.human.people)});
  human_args.insert(human_args.end(), {"--out", l.human_dataset, "--force"});
  Stage human = stage("datasets/human", "dataset", "the people's dataset of the reference expressions",
                      {retarget_command(human_args)});
  depend_on_face_model(recipe, l, human);
  human.inputs.push_back(recipe.human.recipes);
  stages.push_back(std::move(human));

  if (recipe.extras.pictures) stages.push_back(pictures_stage(recipe, l));
  if (recipe.extras.geometry_demo)
    stages.push_back(stage("geometry", "geometry", "the geometry core's demo (DR round trip, deformation transfer)",
                           {retarget_command({"demo", "--out", path_in(l.run, "geometry")})}));

  add_vae_stage(recipe, "avatar_vae", "datasets/avatar", l.avatar_dataset, l.avatar_vae, stages);
  add_vae_stage(recipe, "human_vae", "datasets/human", l.human_dataset, l.human_vae, stages);

  // The CycleGAN+LFD baseline needs the two VAEs alone (no correspondences, no comparisons), so
  // every budget's evaluation shares it.
  std::vector<std::string> cyclegan_sets{"data.human_vae=" + l.human_vae, "data.avatar_vae=" + l.avatar_vae};
  if (auto it = recipe.training.find("cyclegan"); it != recipe.training.end())
    cyclegan_sets.insert(cyclegan_sets.end(), it->second.begin(), it->second.end());
  Stage cyclegan = training_stage("runs/cyclegan", "the CycleGAN+LFD baseline between the two VAEs, and its bundle",
                                  path_in(recipe.profile, "cyclegan.yaml"), cyclegan_sets, l.cyclegan,
                                  {retarget_command({"export", l.cyclegan, "--out", l.cyclegan_bundle()})});
  cyclegan.after = {"runs/avatar_vae", "runs/human_vae"};
  stages.push_back(std::move(cyclegan));

  std::vector<std::string> meaning{"avatar", "meaning", "--rig", l.rig, "--face-model", l.face_model};
  if (!recipe.avatar.meaning_names) meaning.push_back("--no-names");
  meaning.insert(meaning.end(), {"--out", l.proposed});
  Stage proposed = stage("proposed", "meaning", "the controller table proposed from the rig's geometry (the prior)",
                         {retarget_command(meaning)});
  depend_on_rig(recipe, l, proposed);
  depend_on_face_model(recipe, l, proposed);
  stages.push_back(std::move(proposed));

  Stage faces = stage(
      "test_faces", "faces", "the unseen people's references and random blends, as meshes",
      {retarget_command({"faces", l.human_dataset, "--blends", std::to_string(recipe.test_faces.blends), "--blend-seed",
                         std::to_string(recipe.test_faces.blend_seed), "--out", l.test_faces, "--force"})});
  faces.after.push_back("datasets/human");
  stages.push_back(std::move(faces));
}

}  // namespace retarget
