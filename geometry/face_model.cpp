#include "geometry/face_model.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <exception>
#include <filesystem>
#include <set>

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "geometry/landmarks.h"
#include "geometry/mesh_io.h"

namespace retarget {

namespace fs = std::filesystem;

namespace {

// `file` relative to the folder of the YAML file, unless absolute.
std::string resolve(const fs::path& folder, const std::string& file) {
  const fs::path p(file);
  return (p.is_absolute() ? p : folder / p).lexically_normal().string();
}

std::string read_file_key(const ConfigNode& node, const std::string& key, const fs::path& folder) {
  const std::string file = node.child(key).as<std::string>();
  if (file.empty()) node.child(key).fail("expected a mesh file name, got an empty string");
  const std::string path = resolve(folder, file);
  if (!fs::is_regular_file(path)) node.child(key).fail("mesh file not found: " + path);
  return path;
}

struct ShapeEntry {
  std::string name;
  std::string path;
  std::string where;  // "face_model.yaml:12: expressions[3]"
};

// Reads a list of {name, file} entries, rejecting duplicate names.
std::vector<ShapeEntry> shape_entries(const ConfigNode& root, const std::string& key, const fs::path& folder) {
  std::vector<ShapeEntry> entries;
  if (!root.has(key)) return entries;
  const ConfigNode list = root.child(key);
  if (!list.is_sequence() && !list.is_null()) list.fail("expected a list of {name, file} entries");
  std::map<std::string, size_t> seen;
  for (size_t k = 0; k < list.size(); ++k) {
    const ConfigNode item = list.at(k);
    if (!item.is_map()) item.fail("expected {name: ..., file: ...}");
    item.reject_unknown_keys({"name", "file"});
    ShapeEntry entry;
    entry.name = item.child("name").as<std::string>();
    if (entry.name.empty()) item.child("name").fail("expected a name, got an empty string");
    const auto [it, inserted] = seen.emplace(entry.name, k);
    if (!inserted)
      item.child("name").fail("duplicate name \"" + entry.name + "\" (also " + key + "[" + std::to_string(it->second) +
                              "])");
    entry.path = read_file_key(item, "file", folder);
    entry.where = item.where();
    entries.push_back(std::move(entry));
  }
  return entries;
}

// Reads the shape meshes in parallel (OBJ parsing dominates loading a model); errors are
// reported for the first failing entry in file order, so messages do not depend on timing.
std::vector<Blendshape> read_shapes(const std::vector<ShapeEntry>& entries, const Mesh& neutral, bool offsets) {
  const int n = static_cast<int>(entries.size());
  std::vector<Blendshape> shapes(n);
  std::vector<std::exception_ptr> errors(n);
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < n; ++k) {
    try {
      Mesh mesh = read_mesh(entries[k].path);
      if (mesh.vertex_count() != neutral.vertex_count())
        throw Error(entries[k].where, entries[k].path + " has " + std::to_string(mesh.vertex_count()) +
                                          " vertices but the neutral " + neutral.source + " has " +
                                          std::to_string(neutral.vertex_count()));
      shapes[k].name = entries[k].name;
      shapes[k].offset = offsets ? mesh.vertices : Positions(mesh.vertices - neutral.vertices);
    } catch (...) {
      errors[k] = std::current_exception();
    }
  }
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  return shapes;
}

std::string file_stem_for(const std::string& name, std::set<std::string>& used) {
  std::string stem;
  for (char c : name) stem += (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-') ? c : '_';
  if (stem.empty()) stem = "shape";
  // Case-insensitive uniqueness, so the folder survives a copy to macOS or Windows.
  auto lower = [](std::string t) {
    for (char& c : t) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return t;
  };
  std::string unique = stem;
  for (int k = 2; !used.insert(lower(unique)).second; ++k) unique = stem + "_" + std::to_string(k);
  return unique;
}

}  // namespace

int FaceModel::expression_index(const std::string& name) const {
  for (size_t k = 0; k < expressions.size(); ++k)
    if (expressions[k].name == name) return static_cast<int>(k);
  return -1;
}

Positions FaceModel::person(const Eigen::VectorXd& identity) const {
  if (identity.size() > static_cast<Eigen::Index>(identities.size()))
    throw Error(source.empty() ? name : source, std::to_string(identity.size()) +
                                                    " identity coefficients given but the model has " +
                                                    std::to_string(identities.size()) + " identity modes");
  Positions out = neutral.vertices;
  for (Eigen::Index i = 0; i < identity.size(); ++i)
    if (identity[i] != 0) out += identity[i] * identities[i].offset;
  return out;
}

Positions FaceModel::expression(const Positions& person, const std::map<std::string, double>& weights) const {
  if (person.rows() != neutral.vertices.rows())
    throw Error(source.empty() ? name : source, "a face with " + std::to_string(person.rows()) +
                                                    " vertices given but the model has " +
                                                    std::to_string(neutral.vertices.rows()));
  Positions out = person;
  for (const auto& [shape, weight] : weights) {
    const int k = expression_index(shape);
    if (k < 0)
      throw Error(source.empty() ? name : source,
                  "unknown expression blendshape \"" + shape + "\" (the model has " +
                      std::to_string(expressions.size()) + " expressions" +
                      (expressions.empty() ? "" : ", e.g. \"" + expressions.front().name + "\"") + ")");
    if (weight != 0) out += weight * expressions[k].offset;
  }
  return out;
}

FaceModel load_face_model(const std::string& path_in) {
  fs::path path(path_in);
  if (fs::is_directory(path)) path /= "face_model.yaml";
  if (!fs::is_regular_file(path)) throw Error(path.string(), "face model file not found");
  const ConfigNode root = ConfigNode::load_file(path.string());
  if (!root.is_map()) root.fail("expected a map with neutral, identities and expressions");
  root.reject_unknown_keys({"name", "units", "neutral", "shapes", "identities", "expressions", "landmarks", "eyes"});
  const fs::path folder = path.parent_path();

  FaceModel model;
  model.source = path.string();
  model.name = fs::absolute(path).parent_path().filename().string();
  root.get("name", model.name);
  root.get("units", model.units);
  std::string shapes = "absolute";
  root.get("shapes", shapes);
  if (shapes != "absolute" && shapes != "offsets")
    root.child("shapes").fail("expected \"absolute\" or \"offsets\", got \"" + shapes + "\"");

  const std::string neutral_path = read_file_key(root, "neutral", folder);
  model.neutral = read_mesh(neutral_path);
  const std::vector<ShapeEntry> identities = shape_entries(root, "identities", folder);
  const std::vector<ShapeEntry> expressions = shape_entries(root, "expressions", folder);
  model.identities = read_shapes(identities, model.neutral, shapes == "offsets");
  model.expressions = read_shapes(expressions, model.neutral, shapes == "offsets");

  const int n = model.neutral.vertex_count();
  read_landmark_sections(root, n, neutral_path, model.landmarks, model.eyes);
  return model;
}

void write_face_model(const std::string& folder, const FaceModel& model) {
  const fs::path dir(folder);
  const Mesh& neutral = model.neutral;
  write_mesh((dir / "neutral.obj").string(), neutral);

  YAML::Emitter yaml;
  yaml << YAML::BeginMap;
  yaml << YAML::Key << "name" << YAML::Value << model.name;
  yaml << YAML::Key << "units" << YAML::Value << model.units;
  yaml << YAML::Key << "neutral" << YAML::Value << "neutral.obj";
  yaml << YAML::Key << "shapes" << YAML::Value << "absolute";
  // Distinct file names even when two shape names map to the same safe stem.
  auto write_shapes = [&](const char* key, const std::vector<Blendshape>& shapes) {
    std::set<std::string> used;
    yaml << YAML::Key << key << YAML::Value << YAML::BeginSeq;
    for (const Blendshape& shape : shapes) {
      const std::string file = std::string(key) + "/" + file_stem_for(shape.name, used) + ".obj";
      if (shape.offset.rows() != neutral.vertices.rows())
        throw Error(folder, std::string(key) + " \"" + shape.name + "\" has " + std::to_string(shape.offset.rows()) +
                                " vertices but the neutral has " + std::to_string(neutral.vertices.rows()));
      write_mesh((dir / file).string(), with_positions(neutral, neutral.vertices + shape.offset));
      yaml << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << shape.name << YAML::Key << "file"
           << YAML::Value << file << YAML::EndMap;
    }
    yaml << YAML::EndSeq;
  };
  write_shapes("identities", model.identities);
  write_shapes("expressions", model.expressions);
  if (!model.landmarks.empty()) {
    yaml << YAML::Key << "landmarks" << YAML::Value << YAML::Flow << YAML::BeginMap;
    for (const auto& [name, index] : model.landmarks) yaml << YAML::Key << name << YAML::Value << index;
    yaml << YAML::EndMap;
  }
  if (!model.eyes.left.empty() || !model.eyes.right.empty()) {
    yaml << YAML::Key << "eyes" << YAML::Value << YAML::BeginMap;
    yaml << YAML::Key << "left" << YAML::Value << YAML::Flow << model.eyes.left;
    yaml << YAML::Key << "right" << YAML::Value << YAML::Flow << model.eyes.right;
    yaml << YAML::EndMap;
  }
  yaml << YAML::EndMap;
  write_file_atomically((dir / "face_model.yaml").string(), [&](std::ostream& out) { out << yaml.c_str() << "\n"; });
}

std::vector<ExpressionRecipe> load_expression_recipes(const std::string& path) {
  const ConfigNode root = ConfigNode::load_file(path);
  if (!root.is_map()) root.fail("expected a map with a `recipes` list");
  root.reject_unknown_keys({"recipes"});
  const ConfigNode list = root.child("recipes");
  if (!list.is_sequence()) list.fail("expected a list of {name, weights} entries");
  if (list.size() == 0) list.fail("expected at least one recipe");
  std::vector<ExpressionRecipe> recipes;
  std::map<std::string, size_t> seen;
  for (size_t k = 0; k < list.size(); ++k) {
    const ConfigNode item = list.at(k);
    if (!item.is_map()) item.fail("expected {name: ..., weights: {blendshape: weight, ...}}");
    item.reject_unknown_keys({"name", "weights"});
    ExpressionRecipe recipe;
    recipe.name = item.child("name").as<std::string>();
    if (recipe.name.empty()) item.child("name").fail("expected a name, got an empty string");
    const auto [it, inserted] = seen.emplace(recipe.name, k);
    if (!inserted)
      item.child("name").fail("duplicate recipe name \"" + recipe.name + "\" (also recipes[" +
                              std::to_string(it->second) + "])");
    if (item.has("weights")) {
      const ConfigNode weights = item.child("weights");
      if (!weights.is_map() && !weights.is_null()) weights.fail("expected a map {blendshape: weight}");
      if (weights.is_map())
        for (const auto& entry : weights.yaml()) {
          const std::string shape = entry.first.as<std::string>();
          const ConfigNode value = weights.child(shape);
          const double w = value.as<double>();
          if (!std::isfinite(w)) value.fail("expected a finite weight, got " + std::to_string(w));
          recipe.weights[shape] = w;
        }
    }
    recipes.push_back(std::move(recipe));
  }
  return recipes;
}

std::map<std::string, double> recipe_weights(const std::vector<ExpressionRecipe>& recipes, const std::string& name,
                                             const std::string& recipes_file) {
  const auto it =
      std::find_if(recipes.begin(), recipes.end(), [&](const ExpressionRecipe& r) { return r.name == name; });
  if (it == recipes.end()) throw Error(recipes_file, "has no recipe for the expression \"" + name + "\"");
  return it->weights;
}

void write_expression_recipes(const std::string& path, const std::vector<ExpressionRecipe>& recipes) {
  YAML::Emitter y;
  y.SetDoublePrecision(17);
  y << YAML::BeginMap << YAML::Key << "recipes" << YAML::Value << YAML::BeginSeq;
  for (const ExpressionRecipe& r : recipes) {
    y << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << r.name << YAML::Key << "weights"
      << YAML::Value << YAML::BeginMap;
    for (const auto& [shape, weight] : r.weights) y << YAML::Key << shape << YAML::Value << weight;
    y << YAML::EndMap << YAML::EndMap;
  }
  y << YAML::EndSeq << YAML::EndMap;
  write_file_atomically(path, [&](std::ostream& out) { out << y.c_str() << "\n"; });
}

}  // namespace retarget
