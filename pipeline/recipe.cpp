#include "pipeline/recipe.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>

#include "core/config_base.h"
#include "core/error.h"
#include "train/train_config.h"

namespace fs = std::filesystem;

namespace retarget {

namespace {

// A path value read against the file that wrote it, or the working folder for an override.
std::string resolve_path(const ConfigNode& root, const std::string& key, const std::string& value) {
  if (value.empty() || fs::path(value).is_absolute() || value == "synthetic" || value.rfind("synthetic/", 0) == 0)
    return value;
  const std::string source = root.source(key);
  if (source.rfind("--", 0) == 0) return fs::absolute(value).lexically_normal().string();
  return (fs::absolute(source).parent_path() / value).lexically_normal().string();
}

void read_path(const ConfigNode& root, const ConfigNode& section, const std::string& key, std::string& value) {
  if (!section.has(key)) return;
  section.get(key, value);
  value = resolve_path(root, key_path(section.path(), key), value);
}

// An optional section: a null node (every key at its default) when the recipe leaves it out.
ConfigNode section(const ConfigNode& root, const std::string& key) {
  return root.has(key) ? root.child(key) : ConfigNode::parse("{}", root.file() + ": " + key);
}

void read_human(const ConfigNode& root, RecipeHuman& human) {
  const ConfigNode node = root.child("human");
  node.reject_unknown_keys({"face_model", "recipes", "people"});
  read_path(root, node, "face_model", human.face_model);
  read_path(root, node, "recipes", human.recipes);
  node.get("people", human.people);
}

void read_avatar(const ConfigNode& root, RecipeAvatar& avatar) {
  const ConfigNode node = root.child("avatar");
  node.reject_unknown_keys({"rig", "init", "table", "meaning_names", "samples"});
  read_path(root, node, "rig", avatar.rig);
  node.get("init", avatar.init);
  read_path(root, node, "table", avatar.table);
  node.get("meaning_names", avatar.meaning_names);
  node.get("samples", avatar.samples);
}

void read_training(const ConfigNode& root, Recipe& recipe) {
  if (!root.has("training")) return;
  const ConfigNode node = root.child("training");
  node.reject_unknown_keys({"avatar_vae", "human_vae", "translation", "cyclegan", "processes"});
  node.get("processes", recipe.training_processes);
  for (const char* name : {"avatar_vae", "human_vae", "translation", "cyclegan"}) {
    if (!node.has(name)) continue;
    std::vector<std::string> sets;
    node.get(name, sets);
    for (size_t i = 0; i < sets.size(); ++i)
      if (sets[i].find('=') == std::string::npos || sets[i].front() == '=')
        node.child(name).at(i).fail("expected key.path=value (as --set takes), got \"" + sets[i] + "\"");
    recipe.training[name] = sets;
  }
}

void read_method(const ConfigNode& root, RecipeMethod& method) {
  const ConfigNode node = section(root, "method");
  node.reject_unknown_keys({"folder", "budget", "search", "annotation_blends", "annotation_people"});
  node.get("folder", method.folder);
  node.get("budget", method.budget);
  node.get("search", method.search);
  node.get("annotation_blends", method.annotation_blends);
  node.get("annotation_people", method.annotation_people);
}

void read_annotators(const ConfigNode& root, RecipeAnnotators& annotators) {
  const ConfigNode node = section(root, "annotators");
  node.reject_unknown_keys({"kind", "simulate", "poll_seconds"});
  node.get("kind", annotators.kind);
  node.get("poll_seconds", annotators.poll_seconds);
  if (!node.has("simulate")) return;
  const ConfigNode simulate = node.child("simulate");
  simulate.reject_unknown_keys(simulate_setting_names());
  for (const std::string& name : simulate_setting_names())
    if (simulate.has(name)) annotators.simulate[name] = simulate.child(name).as<std::string>();
}

}  // namespace

const std::vector<std::string>& simulate_setting_names() {
  static const std::vector<std::string> names = {
      "noise",          "weber",       "draw-margin", "draw-rate", "lapse-rate", "fatigue", "share-spread",
      "neighbour-rate", "reread-rate", "drop-rate",   "oracle",    "annotators", "name",    "reading-seed"};
  return names;
}

void Recipe::validate() const {
  require(!human.face_model.empty(), "human.face_model", "expected a face model YAML or `synthetic`");
  require(!human.recipes.empty(), "human.recipes", "expected the expression recipes YAML");
  require_non_negative(human.people, "human.people");
  require(!avatar.rig.empty(), "avatar.rig", "expected a rig folder, a .gltf/.glb file or synthetic/<name>");
  require(!avatar.synthetic() || !avatar.synthetic_name().empty(), "avatar.rig",
          "synthetic/<name> names one of `retarget synth`'s avatars (e.g. synthetic/fox)");
  require_non_negative(avatar.samples, "avatar.samples");
  require(!profile.empty(), "profile",
          "expected a folder with avatar_vae.yaml, human_vae.yaml, translation.yaml and cyclegan.yaml");
  require(training_processes >= 1 && training_processes <= 256, "training.processes",
          fmt::format("expected 1..256 data-parallel workers, got {}", training_processes));
  require_non_negative(test_faces.blends, "test_faces.blends");
  require(
      !method.folder.empty() && !fs::path(method.folder).is_absolute() && method.folder.find("..") == std::string::npos,
      "method.folder", "expected a folder inside the run folder (relative, no ..), got \"" + method.folder + "\"");
  require_positive(method.budget, "method.budget");
  require(method.search == "belief" || method.search == "champions" || method.search == "map", "method.search",
          "expected belief, champions or map, got \"" + method.search + "\"");
  require_non_negative(method.annotation_blends, "method.annotation_blends");
  require_positive(method.annotation_people, "method.annotation_people");
  require(annotators.kind == "simulated" || annotators.kind == "people", "annotators.kind",
          "expected simulated or people, got \"" + annotators.kind + "\"");
  require(annotators.kind == "simulated" || annotators.simulate.empty(), "annotators.simulate",
          "only with kind: simulated");
  require_positive(annotators.poll_seconds, "annotators.poll_seconds");
  // Files that must exist before anything runs (a synthetic model or rig is made by the run).
  auto exists = [](const std::string& path, const std::string& key, const std::string& what) {
    require(fs::exists(path), key, fmt::format("{} not found: {}", what, path));
  };
  if (!human.synthetic()) exists(human.face_model, "human.face_model", "face model");
  exists(human.recipes, "human.recipes", "expression recipes");
  if (!avatar.synthetic()) exists(avatar.rig, "avatar.rig", "rig");
  if (!avatar.table.empty()) exists(avatar.table, "avatar.table", "controller table");
  for (const char* name : {"avatar_vae.yaml", "human_vae.yaml", "translation.yaml", "cyclegan.yaml"})
    exists((fs::path(profile) / name).string(), "profile", std::string("the profile's ") + name);
}

Recipe load_recipe(const std::string& path, const std::vector<std::string>& overrides) {
  ConfigNode root = load_config_with_overrides(path, overrides);
  root.reject_unknown_keys({"human", "avatar", "profile", "training", "test_faces", "method", "annotators", "extras"});
  Recipe recipe;
  recipe.file = path;
  try {
    read_human(root, recipe.human);
    read_avatar(root, recipe.avatar);
    read_path(root, root, "profile", recipe.profile);
    read_training(root, recipe);
    const ConfigNode faces = section(root, "test_faces");
    faces.reject_unknown_keys({"blends", "blend_seed"});
    faces.get("blends", recipe.test_faces.blends);
    faces.get("blend_seed", recipe.test_faces.blend_seed);
    read_method(root, recipe.method);
    read_annotators(root, recipe.annotators);
    const ConfigNode extras = section(root, "extras");
    extras.reject_unknown_keys({"pictures", "geometry_demo"});
    extras.get("pictures", recipe.extras.pictures);
    extras.get("geometry_demo", recipe.extras.geometry_demo);
    recipe.validate();
  } catch (const Error& e) {
    rethrow_with_source(root, e);
  }
  recipe.text = YAML::Dump(root.yaml()) + "\n";
  return recipe;
}

}  // namespace retarget
