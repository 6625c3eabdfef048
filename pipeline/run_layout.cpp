#include "pipeline/run_layout.h"

#include <filesystem>

namespace fs = std::filesystem;

namespace retarget {

namespace {

// The rig's name: its folder's, or its glTF file's without the extension.
std::string rig_name(const std::string& rig) {
  const fs::path p = fs::path(rig).lexically_normal();
  const fs::path last = p.filename().empty() ? p.parent_path().filename() : p.filename();
  return fs::is_directory(p) || last.extension().empty() ? last.string() : last.stem().string();
}

}  // namespace

std::string path_in(const std::string& folder, const std::string& name) { return (fs::path(folder) / name).string(); }

std::string RunLayout::round(int number) const { return path_in(path_in(method, "rounds"), std::to_string(number)); }

RunLayout run_layout(const Recipe& recipe, const std::string& run) {
  RunLayout l;
  l.run = run;
  l.synth = path_in(run, "synth");
  l.rig_source = recipe.avatar.synthetic() ? path_in(path_in(l.synth, "avatars"), recipe.avatar.synthetic_name())
                                           : recipe.avatar.rig;
  l.rig = recipe.avatar.init ? path_in(path_in(run, "avatar"), rig_name(l.rig_source)) : l.rig_source;
  const std::string rig_folder = fs::is_directory(l.rig_source) || recipe.avatar.synthetic()
                                     ? l.rig_source
                                     : fs::path(l.rig_source).parent_path().string();
  l.table = recipe.avatar.table.empty() ? path_in(rig_folder, "correspondence.yaml") : recipe.avatar.table;
  l.face_model =
      recipe.human.synthetic() ? path_in(path_in(l.synth, "human"), "face_model.yaml") : recipe.human.face_model;
  l.avatar_dataset = path_in(path_in(run, "datasets"), "avatar");
  l.human_dataset = path_in(path_in(run, "datasets"), "human");
  l.avatar_vae = path_in(path_in(run, "runs"), "avatar_vae");
  l.human_vae = path_in(path_in(run, "runs"), "human_vae");
  l.cyclegan = path_in(path_in(run, "runs"), "cyclegan");
  l.proposed = path_in(run, "proposed.yaml");
  l.test_faces = path_in(run, "test_faces");
  l.method = path_in(run, recipe.method.folder);
  return l;
}

}  // namespace retarget
