#include "geometry/rig.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <numeric>
#include <set>
#include <unordered_map>

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "geometry/landmarks.h"
#include "geometry/mesh_io.h"
#include "geometry/rig_parts.h"
#include "geometry/text_lines.h"

namespace retarget {

namespace fs = std::filesystem;

int Rig::controller_index(const std::string& controller_name) const {
  for (int c = 0; c < controller_count(); ++c)
    if (controllers[c].name == controller_name) return c;
  return -1;
}

std::vector<std::string> Rig::still_controllers() const {
  std::vector<std::string> names;
  for (const Controller& c : controllers)
    if (c.offset.size() == 0 || c.offset.cwiseAbs().maxCoeff() * std::max(std::abs(c.min), std::abs(c.max)) == 0)
      names.push_back(c.name);
  return names;
}

Positions Rig::evaluate(const Eigen::VectorXd& weights) const {
  if (weights.size() != controller_count())
    throw Error(source.empty() ? "rig" : source, "expected " + std::to_string(controller_count()) +
                                                     " controller weights, got " + std::to_string(weights.size()));
  Positions positions = neutral.vertices;
  for (int c = 0; c < controller_count(); ++c)
    if (weights[c] != 0) positions.noalias() += weights[c] * controllers[c].offset;
  return positions;
}

namespace {

std::string lowercase(std::string text) {
  for (char& ch : text) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return text;
}

// `file` as written in rig.yaml, resolved against the yaml's folder; throws naming the key
// and the resolved path when it does not exist.
std::string resolve_existing(const ConfigNode& node, const fs::path& folder) {
  const fs::path written = node.as<std::string>();
  const fs::path resolved = (written.is_absolute() ? written : folder / written).lexically_normal();
  std::error_code ec;
  if (!fs::exists(resolved, ec)) node.fail("file not found: " + resolved.string());
  if (fs::is_directory(resolved, ec)) node.fail("expected a mesh file, got the folder " + resolved.string());
  return resolved.string();
}

// read_mesh() with the key that named the file in front of its message.
Mesh read_mesh_for(const ConfigNode& node, const std::string& path) {
  try {
    return read_mesh(path);
  } catch (const Error& e) {
    throw Error(node.where(), e.what());
  }
}

}  // namespace

namespace rig_yaml_detail {

// A part's vertices as rig.yaml writes them: indices and inclusive [first, last] ranges, each
// checked against the neutral's vertex count; returned ascending and distinct.
std::vector<int> part_vertices(const ConfigNode& list, int vertex_count, const std::string& mesh_path) {
  if (!list.is_sequence() || list.size() == 0)
    list.fail("expected a list of vertex indices and [first, last] ranges, e.g. [12, [100, 199]]");
  std::vector<int> out;
  auto check = [&](const ConfigNode& node, int64_t index) {
    if (index < 0 || index >= vertex_count)
      node.fail("vertex " + std::to_string(index) + " is out of range (" + mesh_path + " has " +
                std::to_string(vertex_count) + " vertices)");
  };
  for (size_t k = 0; k < list.size(); ++k) {
    const ConfigNode item = list.at(k);
    if (item.is_sequence()) {
      const std::vector<int64_t> range = item.as<std::vector<int64_t>>();
      if (range.size() != 2 || range[0] > range[1]) item.fail("expected a range [first, last] with first <= last");
      check(item, range[0]);
      check(item, range[1]);
      for (int64_t v = range[0]; v <= range[1]; ++v) out.push_back(static_cast<int>(v));
    } else {
      const int64_t v = item.as<int64_t>();
      check(item, v);
      out.push_back(static_cast<int>(v));
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// The `parts:` section into rig.parts. {mesh: NAME} entries take over the part load_rig_gltf
// made of that mesh (renamed, their kind set), or cover the first mesh's vertices; `kind`
// defaults to what the part's name, else the mesh's name, says (part_kind_from_name).
void read_parts(const ConfigNode& root, Rig& rig, const std::string& mesh_path, bool gltf) {
  if (!root.has("parts")) return;
  const ConfigNode section = root.child("parts");
  if (!section.is_map()) section.fail("expected a map {part name: {mesh: NAME} or {vertices: [..]}, ...}");
  std::vector<RigPart> parts;
  std::set<std::string> from_yaml;  // meshes the section names
  for (const auto& entry : section.yaml()) {
    const std::string name = entry.first.as<std::string>();
    const ConfigNode item = section.child(name);
    if (!item.is_map()) item.fail("expected {mesh: NAME} or {vertices: [..]}, with an optional kind");
    item.reject_unknown_keys({"mesh", "vertices", "kind"});
    if (item.has("mesh") == item.has("vertices")) item.fail("expected exactly one of `mesh:` and `vertices:`");
    RigPart part;
    part.name = name;
    if (item.has("vertices")) {
      part.vertices = part_vertices(item.child("vertices"), rig.neutral.vertex_count(), mesh_path);
    } else {
      const ConfigNode mesh = item.child("mesh");
      if (!gltf) mesh.fail("`mesh:` names a glTF mesh; this rig's meshes are files (use `vertices:`)");
      part.mesh = mesh.as<std::string>();
      if (!from_yaml.insert(part.mesh).second) mesh.fail("mesh \"" + part.mesh + "\" is named by another part too");
      const auto it = std::find(rig.gltf_meshes.begin(), rig.gltf_meshes.end(), part.mesh);
      if (it == rig.gltf_meshes.begin()) {  // the first mesh: the vertices before the appended ones
        int end = rig.neutral.vertex_count();
        for (const RigPart& p : rig.parts)
          if (!p.mesh.empty() && !p.vertices.empty()) end = std::min(end, p.vertices.front());
        part.vertices.resize(end);
        std::iota(part.vertices.begin(), part.vertices.end(), 0);
      } else {
        for (const RigPart& p : rig.parts)
          if (p.mesh == part.mesh) part.vertices = p.vertices;
      }
    }
    if (item.has("kind")) {
      const ConfigNode kind = item.child("kind");
      const std::optional<PartKind> parsed = parse_part_kind(kind.as<std::string>());
      if (!parsed) kind.fail("expected eye_left, eye_right, teeth, tongue or other");
      part.kind = *parsed;
    } else {
      part.kind = part_kind_from_name(name).value_or(part_kind_from_name(part.mesh).value_or(PartKind::other));
    }
    parts.push_back(std::move(part));
  }
  // The appended meshes' own parts stay unless a yaml part names their mesh.
  std::vector<RigPart> kept;
  for (RigPart& p : rig.parts)
    if (p.mesh.empty() || !from_yaml.count(p.mesh)) kept.push_back(std::move(p));
  for (RigPart& p : parts) kept.push_back(std::move(p));
  std::set<std::string> names;
  for (const RigPart& p : kept)
    if (!names.insert(p.name).second)
      section.fail("two parts are named \"" + p.name + "\" (a mesh appended to the avatar is a part of its name)");
  rig.parts = std::move(kept);
}

// rig.yaml with `gltf:` (see geometry/rig.h).
Rig load_gltf_rig_yaml(const ConfigNode& root, const fs::path& yaml_path, const fs::path& folder) {
  for (const char* key : {"neutral", "targets", "controllers"})
    if (root.has(key))
      root.child(key).fail(
          "not allowed with `gltf:`: the controllers are the glTF file's morph targets (remove this key, or "
          "describe the rig with OBJ files and no `gltf:`)");
  if (root.has("mesh") && root.has("meshes"))
    root.child("meshes").fail("give `mesh:` (one mesh) or `meshes:` (a list), not both");
  const ConfigNode gltf_node = root.child("gltf");
  const std::string gltf_path = resolve_existing(gltf_node, folder);
  GltfRigOptions options;
  if (root.has("mesh")) options.meshes = {root.child("mesh").as<std::string>()};
  if (root.has("meshes")) {
    const ConfigNode list = root.child("meshes");
    options.meshes = list.as<std::vector<std::string>>();
    if (options.meshes.empty()) list.fail("expected at least one mesh name");
    options.find_parts = false;
  }
  auto load = [&](const GltfRigOptions& o) {
    try {
      return load_rig_gltf(gltf_path, o);
    } catch (const Error& e) {
      const std::string key = root.has("meshes") ? "meshes" : root.has("mesh") ? "mesh" : "gltf";
      throw Error(root.child(key).where(), e.what());
    }
  };
  Rig rig = load(options);
  // Meshes that `parts:` names but the avatar does not hold yet are appended, in the yaml's order.
  if (root.has("parts") && root.child("parts").is_map()) {
    GltfRigOptions more;
    more.meshes = rig.gltf_meshes;
    more.find_parts = false;
    const ConfigNode parts = root.child("parts");
    for (const auto& entry : parts.yaml()) {
      const ConfigNode item = parts.child(entry.first.as<std::string>());
      if (!item.is_map() || !item.has("mesh")) continue;
      const std::string mesh = item.child("mesh").as<std::string>();
      if (std::find(more.meshes.begin(), more.meshes.end(), mesh) == more.meshes.end()) more.meshes.push_back(mesh);
    }
    if (more.meshes.size() > rig.gltf_meshes.size()) {
      try {
        rig = load_rig_gltf(gltf_path, more);
      } catch (const Error& e) {
        throw Error(root.child("parts").where(), e.what());
      }
    }
  }
  rig.source = yaml_path.string();
  rig.eyes = {};  // the yaml's `eyes:`, else the eye parts (after `parts:` may have renamed them)
  std::error_code ec;
  rig.name = fs::absolute(folder, ec).lexically_normal().filename().string();
  root.get("name", rig.name);
  if (rig.name.empty()) root.child("name").fail("expected a non-empty name");
  root.get("units", rig.units);
  if (rig.units.empty()) root.child("units").fail("expected a unit such as cm, mm or m");
  read_parts(root, rig, gltf_path, true);
  read_landmark_sections(root, rig.neutral.vertex_count(), gltf_path, rig.landmarks, rig.eyes);
  eyes_from_parts(rig);
  return rig;
}

}  // namespace rig_yaml_detail

Rig load_rig_folder(const std::string& rig_yaml_or_folder) {
  std::error_code ec;
  fs::path yaml_path = rig_yaml_or_folder;
  if (!fs::exists(yaml_path, ec)) throw Error(rig_yaml_or_folder, "no such rig folder or rig.yaml file");
  if (fs::is_directory(yaml_path, ec)) {
    yaml_path /= "rig.yaml";
    if (!fs::exists(yaml_path, ec)) throw Error(rig_yaml_or_folder, "this rig folder has no rig.yaml");
  }
  const fs::path folder = yaml_path.has_parent_path() ? yaml_path.parent_path() : fs::path(".");

  const ConfigNode root = ConfigNode::load_file(yaml_path.string());
  root.reject_unknown_keys(
      {"name", "units", "neutral", "targets", "controllers", "landmarks", "eyes", "parts", "gltf", "mesh", "meshes"});
  if (root.has("gltf")) return rig_yaml_detail::load_gltf_rig_yaml(root, yaml_path, folder);
  for (const char* key : {"mesh", "meshes"})
    if (root.has(key)) root.child(key).fail("names a mesh of a glTF file; add `gltf: FILE` (see geometry/rig.h)");

  Rig rig;
  rig.source = yaml_path.string();
  rig.name = fs::absolute(folder, ec).lexically_normal().filename().string();
  if (rig.name.empty()) rig.name = fs::absolute(folder, ec).lexically_normal().parent_path().filename().string();
  root.get("name", rig.name);
  if (rig.name.empty()) root.child("name").fail("expected a non-empty name");
  root.get("units", rig.units);
  if (rig.units.empty()) root.child("units").fail("expected a unit such as cm, mm or m");

  bool offsets = false;
  if (root.has("targets")) {
    const std::string targets = root.child("targets").as<std::string>();
    if (targets != "absolute" && targets != "offsets")
      root.child("targets").fail("expected 'absolute' or 'offsets', got \"" + targets + "\"");
    offsets = targets == "offsets";
  }

  const ConfigNode neutral_node = root.child("neutral");
  const std::string neutral_path = resolve_existing(neutral_node, folder);
  rig.neutral = read_mesh_for(neutral_node, neutral_path);
  const int vertex_count = rig.neutral.vertex_count();

  const ConfigNode list = root.child("controllers");
  if (!list.is_sequence()) list.fail("expected a list of controllers ({name, file, range})");
  if (list.size() == 0) list.fail("expected at least one controller");
  std::unordered_map<std::string, std::string> first_entry;  // name -> where() of its first entry
  for (size_t k = 0; k < list.size(); ++k) {
    const ConfigNode item = list.at(k);
    if (!item.is_map()) item.fail("expected a map {name, file, range}");
    item.reject_unknown_keys({"name", "file", "range"});
    Controller controller;
    const ConfigNode name_node = item.child("name");
    controller.name = name_node.as<std::string>();
    if (controller.name.empty()) name_node.fail("expected a non-empty controller name");
    const auto [previous, inserted] = first_entry.emplace(controller.name, name_node.where());
    if (!inserted)
      name_node.fail("duplicate controller name \"" + controller.name + "\" (first at " + previous->second + ")");

    if (item.has("range")) {
      const ConfigNode range = item.child("range");
      const std::vector<double> bounds = range.as<std::vector<double>>();
      if (bounds.size() != 2) range.fail("expected [min, max], got " + std::to_string(bounds.size()) + " numbers");
      if (!std::isfinite(bounds[0]) || !std::isfinite(bounds[1]))
        range.fail("expected finite numbers [min, max], got [" + range.at(0).yaml().Scalar() + ", " +
                   range.at(1).yaml().Scalar() + "]");
      if (!(bounds[0] < bounds[1]))
        range.fail("expected min < max, got [" + range.at(0).yaml().Scalar() + ", " + range.at(1).yaml().Scalar() +
                   "]");
      controller.min = bounds[0];
      controller.max = bounds[1];
    }

    const ConfigNode file_node = item.child("file");
    const std::string target_path = resolve_existing(file_node, folder);
    const Mesh target = read_mesh_for(file_node, target_path);
    if (target.vertex_count() != vertex_count)
      file_node.fail("target " + target_path + " has " + std::to_string(target.vertex_count()) +
                     " vertices but the neutral " + neutral_path + " has " + std::to_string(vertex_count));
    controller.offset = offsets ? target.vertices : Positions(target.vertices - rig.neutral.vertices);
    rig.controllers.push_back(std::move(controller));
  }

  rig_yaml_detail::read_parts(root, rig, neutral_path, false);
  read_landmark_sections(root, vertex_count, neutral_path, rig.landmarks, rig.eyes);
  eyes_from_parts(rig);
  return rig;
}

Rig load_rig(const std::string& path, const std::string& mesh_name) {
  const std::string extension = lowercase(fs::path(path).extension().string());
  if (extension == ".gltf" || extension == ".glb") return load_rig_gltf(path, mesh_name);
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(path, "no such rig folder, rig.yaml or glTF file");
  const bool folder_or_yaml = fs::is_directory(path, ec) || extension == ".yaml" || extension == ".yml";
  if (!folder_or_yaml)
    throw Error(
        path, "expected a rig folder, a rig.yaml, or a .gltf/.glb file (unsupported extension \"" + extension + "\")");
  if (!mesh_name.empty())
    throw Error(path, "a mesh name (\"" + mesh_name + "\") only selects a mesh in a glTF file, not in a rig folder");
  return load_rig_folder(path);
}

Rig load_rig(const std::string& path, const std::vector<std::string>& gltf_meshes) {
  const std::string extension = lowercase(fs::path(path).extension().string());
  if (gltf_meshes.empty() || (extension != ".gltf" && extension != ".glb")) return load_rig(path);
  GltfRigOptions options;
  options.meshes = gltf_meshes;
  options.find_parts = false;
  return load_rig_gltf(path, options);
}

namespace {

// A file name from a controller name: letters, digits, '-', '_' and '.' are kept, anything
// else becomes '_'; never empty, never hidden.
std::string file_stem(const std::string& name) {
  std::string stem;
  for (char ch : name) {
    const bool keep = std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '_' || ch == '.';
    stem += keep ? ch : '_';
  }
  if (stem.empty() || stem[0] == '.') stem = "_" + stem;
  return stem;
}

}  // namespace

void write_rig_folder(const std::string& folder, const Rig& rig) {
  const fs::path dir = folder;
  // Case-insensitive uniqueness, so the folder also survives a copy to macOS or Windows.
  std::set<std::string> used = {"neutral", "rig"};
  std::vector<std::string> files;
  for (const Controller& controller : rig.controllers) {
    const std::string stem = file_stem(controller.name);
    std::string candidate = stem;
    for (int n = 2; used.count(lowercase(candidate)); ++n) candidate = stem + "_" + std::to_string(n);
    used.insert(lowercase(candidate));
    files.push_back(candidate + ".obj");
  }

  // Meshes first, rig.yaml last: once rig.yaml exists, everything it names exists too.
  write_mesh((dir / "neutral.obj").string(), rig.neutral);
  for (size_t c = 0; c < rig.controllers.size(); ++c) {
    const Controller& controller = rig.controllers[c];
    if (controller.offset.rows() != rig.neutral.vertices.rows())
      throw Error(folder, "controller \"" + controller.name + "\" has " + std::to_string(controller.offset.rows()) +
                              " offset rows but the neutral has " + std::to_string(rig.neutral.vertex_count()) +
                              " vertices");
    write_mesh((dir / files[c]).string(),
               with_positions(rig.neutral, Positions(rig.neutral.vertices + controller.offset)));
  }

  YAML::Emitter out;
  out << YAML::BeginMap;
  if (!rig.name.empty()) out << YAML::Key << "name" << YAML::Value << rig.name;
  out << YAML::Key << "units" << YAML::Value << rig.units;
  out << YAML::Key << "neutral" << YAML::Value << "neutral.obj";
  out << YAML::Key << "targets" << YAML::Value << "absolute";
  out << YAML::Key << "controllers" << YAML::Value << YAML::BeginSeq;
  for (size_t c = 0; c < rig.controllers.size(); ++c) {
    const Controller& controller = rig.controllers[c];
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "name" << YAML::Value << controller.name;
    out << YAML::Key << "file" << YAML::Value << files[c];
    if (controller.min != 0 || controller.max != 1) {
      out << YAML::Key << "range" << YAML::Value << YAML::Flow << YAML::BeginSeq;
      out << shortest_text(controller.min) << shortest_text(controller.max);
      out << YAML::EndSeq;
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  if (!rig.landmarks.empty()) {
    out << YAML::Key << "landmarks" << YAML::Value << YAML::BeginMap;
    for (const auto& [name, index] : rig.landmarks) out << YAML::Key << name << YAML::Value << index;
    out << YAML::EndMap;
  }
  if (!rig.eyes.left.empty() || !rig.eyes.right.empty()) {
    out << YAML::Key << "eyes" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "left" << YAML::Value << YAML::Flow << rig.eyes.left;
    out << YAML::Key << "right" << YAML::Value << YAML::Flow << rig.eyes.right;
    out << YAML::EndMap;
  }
  if (!rig.parts.empty()) {
    // As vertex lists (the folder's meshes are files): runs of consecutive indices as ranges.
    out << YAML::Key << "parts" << YAML::Value << YAML::BeginMap;
    for (const RigPart& part : rig.parts) {
      out << YAML::Key << part.name << YAML::Value << YAML::Flow << YAML::BeginMap;
      out << YAML::Key << "kind" << YAML::Value << to_string(part.kind);
      out << YAML::Key << "vertices" << YAML::Value << YAML::BeginSeq;
      for (size_t k = 0; k < part.vertices.size();) {
        size_t end = k + 1;
        while (end < part.vertices.size() && part.vertices[end] == part.vertices[end - 1] + 1) ++end;
        if (end - k == 1)
          out << part.vertices[k];
        else
          out << YAML::Flow << YAML::BeginSeq << part.vertices[k] << part.vertices[end - 1] << YAML::EndSeq;
        k = end;
      }
      out << YAML::EndSeq << YAML::EndMap;
    }
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  if (!out.good()) throw Error(folder, "cannot write rig.yaml: " + out.GetLastError());
  const std::string text = std::string(out.c_str()) + "\n";
  write_file_atomically((dir / "rig.yaml").string(), [&](std::ostream& stream) { stream << text; });
}

}  // namespace retarget
