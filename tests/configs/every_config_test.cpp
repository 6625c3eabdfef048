// Every YAML file under configs/ loads through the loader of its kind, found at test time: a file
// added there is validated by the rule for its kind, and a file no rule knows fails the test,
// naming the file. The real-data configs name meshes in ../shared/data, which tests never need:
// they are loaded from a copy at the same place in a scratch tree, with one stand-in mesh linked
// at every path they name, so the real loaders check their keys, types, names and vertex indices.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "core/error.h"
#include "geometry/controller_correspondence.h"
#include "geometry/face_model.h"
#include "geometry/mesh_io.h"
#include "geometry/rig.h"
#include "pipeline/recipe.h"
#include "test_support.h"
#include "tests/configs/train_profiles.h"
#include "train/train_config.h"
#include "train/vae_config.h"
#include "translate/cyclegan_config.h"
#include "translate/translation_config.h"

using namespace retarget;
using namespace retarget::test;
using Catch::Contains;
namespace fs = std::filesystem;

namespace {

// Every .yaml or .yml file under configs/, relative to it ("train/quick/avatar_vae.yaml"), sorted.
std::vector<std::string> config_files() { return yaml_files_under(repo_configs()); }

// Scalars of `node` that read as meshes (.obj, .ply, .off) into `meshes`; the largest
// non-negative integer scalar (a vertex index) into `largest`.
void scan(const YAML::Node& node, std::vector<std::string>& meshes, long& largest) {
  if (node.IsMap()) {
    for (const auto& entry : node) scan(entry.second, meshes, largest);
  } else if (node.IsSequence()) {
    for (const auto& item : node) scan(item, meshes, largest);
  } else if (node.IsScalar()) {
    const std::string& text = node.Scalar();
    std::string extension = fs::path(text).extension().string();
    for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (extension == ".obj" || extension == ".ply" || extension == ".off") meshes.push_back(text);
    if (!text.empty() && text.size() < 10 &&
        std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; }))
      largest = std::max(largest, std::stol(text));
  }
}

// The copy of configs/`relative` at the same place below a scratch tree, every mesh it names
// linked to one stand-in grid with more vertices than any index it gives. Returns the copy's path.
std::string with_stand_in_meshes(const std::string& relative) {
  const fs::path source = repo_configs() / relative;
  const fs::path root = process_scratch_dir("stand_in_" + fs::path(relative).parent_path().filename().string() + "_" +
                                            fs::path(relative).stem().string());
  // Deep enough that the paths a config climbs out of the checkout with stay inside the tree.
  const fs::path copy = root / "a/b/c/d/e/f/checkout/configs" / relative;
  fs::create_directories(copy.parent_path());
  fs::copy_file(source, copy);
  std::vector<std::string> meshes;
  long largest = 0;
  scan(YAML::LoadFile(source.string()), meshes, largest);
  const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(largest + 1))));
  const fs::path stand_in = root / "stand_in.obj";
  write_mesh(stand_in.string(), quad_grid(side, side, 1.0, 1.0));  // (side + 1)^2 vertices
  for (const std::string& mesh : meshes) {
    INFO(relative << " names the mesh " << mesh);
    REQUIRE(fs::path(mesh).is_relative());  // configs use paths relative to themselves
    const fs::path at = (copy.parent_path() / mesh).lexically_normal();
    REQUIRE(at.string().rfind(root.string(), 0) == 0);
    fs::create_directories(at.parent_path());
    if (!fs::exists(at)) fs::create_symlink(stand_in, at);
  }
  return copy.string();
}

// Runs `load` and fails the test with the config's own name and the loader's message if it throws.
void expect_loads(const std::string& relative, const std::function<void()>& load) {
  try {
    load();
  } catch (const Error& e) {
    FAIL_CHECK("configs/" << relative << " does not load: " << e.what());
  }
}

void validate_training_config(const std::string& relative) {
  expect_loads(relative, [&] {
    const ConfigNode root = load_profile(repo_configs() / relative, manifest_only_dataset(4));
    if (config_task(root) == "vae")
      (void)read_vae_train_config(root);
    else if (config_task(root) == "cyclegan")
      (void)read_cyclegan_train_config(root);
    else
      (void)read_translation_train_config(root);
  });
}

void validate_recipes(const std::string& relative) {
  expect_loads(relative, [&] { CHECK(!load_expression_recipes((repo_configs() / relative).string()).empty()); });
}

void validate_rig(const std::string& relative) {
  expect_loads(relative, [&] { CHECK(load_rig_folder(with_stand_in_meshes(relative)).controller_count() > 0); });
}

void validate_face_model(const std::string& relative) {
  expect_loads(relative, [&] { CHECK(!load_face_model(with_stand_in_meshes(relative)).expressions.empty()); });
}

void validate_correspondence(const std::string& relative) {
  expect_loads(relative, [&] { CHECK(!load_controller_correspondence((repo_configs() / relative).string()).empty()); });
}

void validate_pipeline_recipe(const std::string& relative) {
  expect_loads(relative, [&] { CHECK(load_recipe((repo_configs() / relative).string(), {}).method.budget > 0); });
}

struct Rule {
  const char* pattern;  // relative to configs/: "<dir>/*.yaml" (one level) or "<dir>/**" (any depth)
  const char* kind;
  void (*validate)(const std::string& relative);
};

const std::vector<Rule>& rules() {
  static const std::vector<Rule> table = {
      {"train/**", "training config (retarget train)", validate_training_config},
      {"expressions/*.yaml", "expression recipes (retarget dataset --recipes)", validate_recipes},
      {"real/*/rig.yaml", "rig (retarget dataset --rig)", validate_rig},
      {"real/*/face_model.yaml", "face model (retarget dataset --face-model)", validate_face_model},
      {"real/*/correspondence.yaml", "controller table (--table)", validate_correspondence},
      {"recipes/*.yaml", "pipeline recipe (retarget pipeline)", validate_pipeline_recipe},
  };
  return table;
}

// True if `relative` matches `pattern`: '*' stands for one path part (or a part of one), "**" at
// the end for anything below.
bool matches(const std::string& pattern, const std::string& relative) {
  if (pattern.size() >= 2 && pattern.compare(pattern.size() - 2, 2, "**") == 0)
    return relative.rfind(pattern.substr(0, pattern.size() - 2), 0) == 0;
  size_t p = 0, r = 0;
  while (p < pattern.size()) {
    if (pattern[p] == '*') {
      const size_t next = pattern.find_first_of("/", p);
      const std::string after = pattern.substr(p + 1, next == std::string::npos ? std::string::npos : next - p - 1);
      const size_t end = relative.find('/', r);
      const std::string part = relative.substr(r, end == std::string::npos ? std::string::npos : end - r);
      if (part.size() < after.size() || part.compare(part.size() - after.size(), after.size(), after) != 0)
        return false;
      p = next == std::string::npos ? pattern.size() : next;
      r = end == std::string::npos ? relative.size() : end;
    } else {
      if (r >= relative.size() || pattern[p] != relative[r]) return false;
      ++p, ++r;
    }
  }
  return r == relative.size();
}

// The rule that validates configs/`relative`; nullptr if none does.
const Rule* rule_for(const std::string& relative) {
  for (const Rule& rule : rules())
    if (matches(rule.pattern, relative)) return &rule;
  return nullptr;
}

}  // namespace

TEST_CASE("every YAML under configs/ loads through the loader of its kind", "[config]") {
  const std::vector<std::string> files = config_files();
  REQUIRE(files.size() >= 14);
  std::set<std::string> kinds;
  for (const std::string& file : files) {
    INFO("configs/" << file);
    const Rule* rule = rule_for(file);
    if (!rule) {
      FAIL_CHECK("configs/" << file
                            << " has no validation: add a rule for its kind to rules() in "
                               "tests/configs/every_config_test.cpp");
      continue;
    }
    kinds.insert(rule->kind);
    rule->validate(file);
  }
  CHECK(kinds.size() == rules().size());  // every rule still has a file to check
}

TEST_CASE("a YAML under configs/ that no rule knows has no validation", "[config]") {
  CHECK(rule_for("train/avatar_vae.yaml") != nullptr);
  CHECK(rule_for("train/good/translation.yaml") != nullptr);
  CHECK(rule_for("expressions/facewarehouse47.yaml") != nullptr);
  CHECK(rule_for("real/lapin/rig.yaml") != nullptr);
  CHECK(rule_for("real/ict/face_model.yaml") != nullptr);
  CHECK(rule_for("real/lapin/correspondence.yaml") != nullptr);
  CHECK(rule_for("real/lapin/landmarks.yaml") == nullptr);
  CHECK(rule_for("expressions/extra/more.yaml") == nullptr);
  CHECK(rule_for("real/rig.yaml") == nullptr);
  CHECK(rule_for("recipes/demo.yaml") != nullptr);
  CHECK(rule_for("new.yaml") == nullptr);
  CHECK(rule_for("trainer/x.yaml") == nullptr);
}

TEST_CASE("the real-data configs agree with each other", "[config]") {
  const Rig lapin = load_rig_folder(with_stand_in_meshes("real/lapin/rig.yaml"));
  const FaceModel ict = load_face_model(with_stand_in_meshes("real/ict/face_model.yaml"));
  std::vector<std::string> controllers, shapes;
  for (const Controller& c : lapin.controllers) controllers.push_back(c.name);
  for (const Blendshape& b : ict.expressions) shapes.push_back(b.name);
  // The rabbit's table names its controllers, each with ICT (ARKit-named) shapes.
  CHECK_NOTHROW(check_controller_correspondence(
      load_controller_correspondence((repo_configs() / "real/lapin/correspondence.yaml").string()), controllers, shapes,
      "configs/real/lapin/correspondence.yaml"));
  // The recipes use only shapes the ICT model has (its header says so).
  for (const ExpressionRecipe& recipe :
       load_expression_recipes((repo_configs() / "expressions/facewarehouse47.yaml").string()))
    for (const auto& [shape, weight] : recipe.weights) {
      INFO(recipe.name << " uses " << shape);
      CHECK(std::find(shapes.begin(), shapes.end(), shape) != shapes.end());
    }
  // The ICT head as a rig has the face model's expressions as its controllers.
  const Rig ict_rig = load_rig_folder(with_stand_in_meshes("real/ict-rig/rig.yaml"));
  std::vector<std::string> rig_controllers;
  for (const Controller& c : ict_rig.controllers) rig_controllers.push_back(c.name);
  CHECK(rig_controllers == shapes);
}
