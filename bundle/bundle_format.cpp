#include "bundle/bundle_format.h"

#include <c10/util/StringUtil.h>
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <future>
#include <nlohmann/json.hpp>
#include <string>
#include <type_traits>

#include "bundle/normalisation.h"
#include "core/config.h"
#include "core/error.h"
#include "core/json_fields.h"
#include "core/log.h"
#include "core/sha256.h"
#include "core/tensor_io.h"
#include "geometry/mesh_io.h"
#include "geometry/topology_fingerprint.h"

namespace retarget {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kFolderHint =
    "a retarget bundle folder holds manifest.yaml, bundle.pt, human_rest.obj and avatar_rest.obj (and rig.pt when it "
    "carries the avatar's rig), written by export_bundle";

template <typename T>
std::string str(const T& value) {
  return c10::str(value);
}

// --- metadata as module attributes, JSON and YAML ------------------------------------------

void add_side_attributes(torch::jit::Module& module, const BundleSideMetadata& m, const std::string& prefix) {
  const auto text = c10::StringType::get();
  const auto integer = c10::IntType::get();
  module.register_attribute(prefix + "name", text, m.name);
  module.register_attribute(prefix + "vertices", integer, m.vertices);
  module.register_attribute(prefix + "faces", integer, m.faces);
  module.register_attribute(prefix + "fingerprint", text, m.fingerprint);
  module.register_attribute(prefix + "latent", integer, m.latent);
  module.register_attribute(prefix + "units", text, m.units);
  module.register_attribute(prefix + "dr_weighting", text, std::string(to_string(m.dr.weighting)));
  module.register_attribute(prefix + "dr_normal_term", c10::BoolType::get(), m.dr.normal_term);
  module.register_attribute(prefix + "dr_normal_weight", c10::FloatType::get(), m.dr.normal_weight);
}

json side_json(const BundleSideMetadata& m) {
  json j = {{"name", m.name},
            {"vertices", m.vertices},
            {"faces", m.faces},
            {"fingerprint", m.fingerprint},
            {"latent", m.latent},
            {"units", m.units},
            {"dr",
             {{"weighting", to_string(m.dr.weighting)},
              {"normal_term", m.dr.normal_term},
              {"normal_weight", m.dr.normal_weight}}}};
  if (!m.still_vertices.empty()) j["still_vertices"] = m.still_vertices;
  return j;
}

json rig_json(const BundleRigMetadata& r) {
  json controllers = json::array();
  for (const BundleController& c : r.controllers)
    controllers.push_back({{"name", c.name}, {"range", json::array({c.min, c.max})}});
  return {{"controllers", std::move(controllers)}, {"millimetres_per_unit", r.millimetres_per_unit}};
}

// Every field of the metadata (the part two exports are compared on).
json metadata_object(const BundleMetadata& m) {
  json j = {{"format", m.format},
            {"format_version", m.format_version},
            {"software_version", m.software_version},
            {"created", m.created},
            {"features", m.features},
            {"human", side_json(m.human)},
            {"avatar", side_json(m.avatar)},
            {"translation", {{"hidden", m.translation_hidden}}}};
  if (m.rig) j["rig"] = rig_json(*m.rig);
  return j;
}

// The first problem of a rig's metadata as (key path below `rig`, message), or an empty key path.
std::pair<std::string, std::string> rig_problem(const BundleRigMetadata& r) {
  if (r.controllers.empty()) return {"controllers", "expected at least one controller"};
  std::map<std::string, size_t> seen;
  for (size_t i = 0; i < r.controllers.size(); ++i) {
    const BundleController& c = r.controllers[i];
    const std::string key = "controllers[" + str(i) + "]";
    if (c.name.empty()) return {key + ".name", "expected a controller name, got an empty string"};
    const auto [at, fresh] = seen.emplace(c.name, i);
    if (!fresh) return {key + ".name", "'" + c.name + "' names controllers[" + str(at->second) + "] too"};
    if (!std::isfinite(c.min) || !std::isfinite(c.max) || !(c.min < c.max))
      return {key + ".range", fmt::format("expected [min, max] with finite min < max, got [{}, {}]", c.min, c.max)};
  }
  if (!std::isfinite(r.millimetres_per_unit) || r.millimetres_per_unit < 0)
    return {"millimetres_per_unit",
            fmt::format("expected a finite number >= 0 (0: unknown), got {}", r.millimetres_per_unit)};
  return {"", ""};
}

BundleRigMetadata parse_rig_json(const JsonFields& fields, const json& object) {
  BundleRigMetadata r;
  const std::string at = fields.where + ": " + kBundleMetadataFile + ": rig";
  const json& controllers = fields.member(object, "controllers", "rig");
  if (!controllers.is_array()) throw Error(at + ".controllers", "expected a list of controllers");
  for (size_t i = 0; i < controllers.size(); ++i) {
    const std::string path = "rig.controllers[" + str(i) + "]";
    BundleController c;
    c.name = fields.get<std::string>(controllers[i], "name", path);
    const json& range = fields.member(controllers[i], "range", path);
    if (!range.is_array() || range.size() != 2 || !range[0].is_number() || !range[1].is_number())
      throw Error(at + ".controllers[" + str(i) + "].range", "expected [min, max]");
    c.min = range[0].get<double>();
    c.max = range[1].get<double>();
    r.controllers.push_back(std::move(c));
  }
  r.millimetres_per_unit = fields.get<double>(object, "millimetres_per_unit", "rig");
  const auto [key, message] = rig_problem(r);
  if (!key.empty()) throw Error(at + "." + key, message);
  return r;
}

BundleSideMetadata parse_side_json(const JsonFields& fields, const json& object, const std::string& path) {
  BundleSideMetadata m;
  m.name = fields.get<std::string>(object, "name", path);
  m.vertices = fields.get<int64_t>(object, "vertices", path);
  m.faces = fields.get<int64_t>(object, "faces", path);
  m.fingerprint = fields.get<std::string>(object, "fingerprint", path);
  m.latent = fields.get<int64_t>(object, "latent", path);
  m.units = fields.get<std::string>(object, "units", path);
  const json& dr = fields.member(object, "dr", path);
  m.dr.weighting = parse_edge_weighting(fields.get<std::string>(dr, "weighting", path + ".dr"),
                                        fields.where + ": " + kBundleMetadataFile + ": " + path + ".dr.weighting");
  m.dr.normal_term = fields.get<bool>(dr, "normal_term", path + ".dr");
  m.dr.normal_weight = fields.get<double>(dr, "normal_weight", path + ".dr");
  if (object.contains("still_vertices")) {
    const json& still = object.at("still_vertices");
    if (!still.is_array())
      throw Error(fields.where, std::string(kBundleMetadataFile) + ": " + path +
                                    ".still_vertices: expected a list of vertex indices");
    for (const json& v : still) {
      if (!v.is_number_integer() || v.get<int64_t>() < 0 || v.get<int64_t>() >= m.vertices)
        throw Error(fields.where, std::string(kBundleMetadataFile) + ": " + path +
                                      ".still_vertices: expected vertex indices in 0.." + str(m.vertices - 1));
      m.still_vertices.push_back(v.get<int64_t>());
    }
  }
  return m;
}

void emit_side(YAML::Emitter& y, const BundleSideMetadata& m) {
  y << YAML::BeginMap;
  y << YAML::Key << "name" << YAML::Value << m.name;
  y << YAML::Key << "vertices" << YAML::Value << m.vertices;
  y << YAML::Key << "faces" << YAML::Value << m.faces;
  y << YAML::Key << "fingerprint" << YAML::Value << m.fingerprint;
  y << YAML::Key << "latent" << YAML::Value << m.latent;
  y << YAML::Key << "units" << YAML::Value << m.units;
  y << YAML::Key << "dr" << YAML::Value << YAML::Flow << YAML::BeginMap;
  y << YAML::Key << "weighting" << YAML::Value << to_string(m.dr.weighting);
  y << YAML::Key << "normal_term" << YAML::Value << m.dr.normal_term;
  y << YAML::Key << "normal_weight" << YAML::Value << m.dr.normal_weight << YAML::EndMap;
  if (!m.still_vertices.empty()) y << YAML::Key << "still_vertices" << YAML::Value << YAML::Flow << m.still_vertices;
  y << YAML::EndMap;
}

std::string manifest_text(const BundleMetadata& m, const std::map<std::string, std::string>& sha256) {
  YAML::Emitter y;
  y.SetDoublePrecision(17);
  y << YAML::BeginMap;
  y << YAML::Key << "format" << YAML::Value << m.format;
  y << YAML::Key << "format_version" << YAML::Value << m.format_version;
  y << YAML::Key << "software_version" << YAML::Value << m.software_version;
  y << YAML::Key << "created" << YAML::Value << m.created;
  y << YAML::Key << "features" << YAML::Value << m.features;
  y << YAML::Key << "human" << YAML::Value;
  emit_side(y, m.human);
  y << YAML::Key << "avatar" << YAML::Value;
  emit_side(y, m.avatar);
  y << YAML::Key << "translation" << YAML::Value << YAML::Flow << YAML::BeginMap;
  y << YAML::Key << "hidden" << YAML::Value << m.translation_hidden << YAML::EndMap;
  if (m.rig) {
    y << YAML::Key << "rig" << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "millimetres_per_unit" << YAML::Value << m.rig->millimetres_per_unit;
    y << YAML::Key << "controllers" << YAML::Value << YAML::BeginSeq;
    for (const BundleController& c : m.rig->controllers) {
      y << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << YAML::DoubleQuoted << c.name;
      y << YAML::Key << "range" << YAML::Value << YAML::Flow << YAML::BeginSeq << c.min << c.max << YAML::EndSeq;
      y << YAML::EndMap;
    }
    y << YAML::EndSeq << YAML::EndMap;
  }
  y << YAML::Key << "files" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "module" << YAML::Value << kBundleModuleFile;
  y << YAML::Key << "human_rest" << YAML::Value << kBundleHumanRestFile;
  y << YAML::Key << "avatar_rest" << YAML::Value << kBundleAvatarRestFile;
  if (m.rig) y << YAML::Key << "rig" << YAML::Value << kBundleRigFile;
  y << YAML::EndMap;
  if (!sha256.empty()) {
    y << YAML::Key << "sha256" << YAML::Value << YAML::BeginMap;
    for (const auto& [file, digest] : sha256) y << YAML::Key << file << YAML::Value << digest;
    y << YAML::EndMap;
  }
  y << YAML::EndMap;
  if (!y.good()) throw Error(kBundleManifestFile, "cannot write the manifest: " + y.GetLastError());
  return std::string(
             "# retarget bundle (see bundle/bundle_format.h): bundle.pt maps raw human DR features [B, Vh, 9]\n"
             "# to raw avatar DR features [B, Va, 9]; load it with torch::jit::load or torch.jit.load\n") +
         y.c_str() + "\n";
}

BundleSideMetadata read_side(const ConfigNode& node) {
  node.reject_unknown_keys({"name", "vertices", "faces", "fingerprint", "latent", "units", "dr", "still_vertices"});
  BundleSideMetadata m;
  node.get_required("name", m.name);
  node.get_required("vertices", m.vertices);
  node.get_required("faces", m.faces);
  node.get_required("fingerprint", m.fingerprint);
  node.get_required("latent", m.latent);
  node.get("units", m.units);
  const ConfigNode dr = node.child("dr");
  dr.reject_unknown_keys({"weighting", "normal_term", "normal_weight"});
  m.dr.weighting = parse_edge_weighting(dr.child("weighting").as<std::string>(), dr.child("weighting").where());
  dr.get_required("normal_term", m.dr.normal_term);
  dr.get_required("normal_weight", m.dr.normal_weight);
  try {
    m.dr.validate();
  } catch (const Error& e) {
    dr.fail(e.what());
  }
  if (m.vertices <= 0) node.child("vertices").fail("expected a positive vertex count");
  if (m.latent <= 0) node.child("latent").fail("expected a positive latent size");
  if (node.has("still_vertices")) {
    m.still_vertices = node.child("still_vertices").as<std::vector<int64_t>>();
    for (size_t i = 0; i < m.still_vertices.size(); ++i)
      if (m.still_vertices[i] < 0 || m.still_vertices[i] >= m.vertices ||
          (i > 0 && m.still_vertices[i] <= m.still_vertices[i - 1]))
        node.child("still_vertices")
            .fail(fmt::format("entry {} ({}): expected ascending vertex indices in 0..{}", i, m.still_vertices[i],
                              m.vertices - 1));
  }
  return m;
}

BundleRigMetadata read_rig(const ConfigNode& node) {
  node.reject_unknown_keys({"millimetres_per_unit", "controllers"});
  BundleRigMetadata r;
  node.get("millimetres_per_unit", r.millimetres_per_unit);
  const ConfigNode controllers = node.child("controllers");
  if (!controllers.is_sequence()) controllers.fail("expected a list of {name: ..., range: [min, max]}");
  for (size_t i = 0; i < controllers.size(); ++i) {
    const ConfigNode c = controllers.at(i);
    c.reject_unknown_keys({"name", "range"});
    BundleController controller;
    c.get_required("name", controller.name);
    const std::vector<double> range = c.child("range").as<std::vector<double>>();
    if (range.size() != 2) c.child("range").fail("expected [min, max]");
    controller.min = range[0];
    controller.max = range[1];
    r.controllers.push_back(std::move(controller));
  }
  const auto [key, message] = rig_problem(r);
  if (!key.empty()) {
    // The node the problem is in: a controller's name or range, the list, or the scale.
    const size_t open = key.find('['), close = key.find(']');
    if (open != std::string::npos && close != std::string::npos) {
      const ConfigNode c = controllers.at(std::stoul(key.substr(open + 1, close - open - 1)));
      c.child(key.substr(close + 2)).fail(message);
    }
    node.child(key).fail(message);
  }
  return r;
}

struct Manifest {
  BundleMetadata metadata;
  std::string module_file = kBundleModuleFile, human_rest_file = kBundleHumanRestFile,
              avatar_rest_file = kBundleAvatarRestFile, rig_file;  // rig_file: empty without a rig
  std::map<std::string, std::string> sha256;                       // file name -> digest (`sha256`)
  std::string sha256_where;                                        // "manifest.yaml:L: sha256" for messages
};

Manifest read_manifest(const ConfigNode& m, const std::string& path) {
  if (!m.is_map() || !m.has("format")) {
    throw Error(path, std::string("not a retarget bundle manifest: it has no \"format: ") + kBundleFormat + "\"");
  }
  Manifest manifest;
  BundleMetadata& d = manifest.metadata;
  d.format = m.child("format").as<std::string>();
  if (d.format != kBundleFormat) {
    m.child("format").fail(std::string("not a retarget bundle manifest: expected \"") + kBundleFormat + "\", got \"" +
                           d.format + "\"");
  }
  d.format_version = m.child("format_version").as<int64_t>();
  if (d.format_version > kBundleFormatVersion) {
    m.child("format_version")
        .fail("written in bundle format " + str(d.format_version) + " by a newer retarget; this build reads up to " +
              str(kBundleFormatVersion));
  }
  m.reject_unknown_keys({"format", "format_version", "software_version", "created", "features", "human", "avatar",
                         "translation", "rig", "files", "sha256"});
  m.get_required("software_version", d.software_version);
  m.get("created", d.created);
  m.get_required("features", d.features);
  if (d.features != kDrWidth) m.child("features").fail("expected " + str(kDrWidth) + " (DR features)");
  d.human = read_side(m.child("human"));
  d.avatar = read_side(m.child("avatar"));
  if (m.has("translation")) {
    const ConfigNode translation = m.child("translation");
    translation.reject_unknown_keys({"hidden"});
    translation.get("hidden", d.translation_hidden);
  }
  if (m.has("rig")) {
    d.rig = read_rig(m.child("rig"));
    manifest.rig_file = kBundleRigFile;
  }
  if (m.has("files")) {
    const ConfigNode files = m.child("files");
    files.reject_unknown_keys({"module", "human_rest", "avatar_rest", "rig"});
    files.get("module", manifest.module_file);
    files.get("human_rest", manifest.human_rest_file);
    files.get("avatar_rest", manifest.avatar_rest_file);
    if (files.has("rig")) {
      if (!d.rig) files.child("rig").fail("the manifest has no rig (no `rig` key) for this file to hold");
      files.get("rig", manifest.rig_file);
    }
  }
  if (m.has("sha256")) {
    const ConfigNode sums = m.child("sha256");
    manifest.sha256_where = sums.where();
    if (!sums.is_map()) sums.fail("expected a map of file name: SHA-256");
    for (const auto& entry : sums.yaml()) {
      if (!entry.first.IsScalar()) sums.fail("expected file names as keys");
      const std::string file = entry.first.Scalar();
      manifest.sha256[file] = sums.child(file).as<std::string>();
    }
    for (const auto& [file, digest] : manifest.sha256) {
      if (file != manifest.module_file && file != manifest.human_rest_file && file != manifest.avatar_rest_file &&
          (manifest.rig_file.empty() || file != manifest.rig_file))
        sums.fail("'" + file + "' is not one of the bundle's files");
      if (digest.size() != 64 || digest.find_first_not_of("0123456789abcdef") != std::string::npos)
        sums.child(file).fail("expected 64 lowercase hex digits (a SHA-256), got \"" + digest + "\"");
    }
  }
  return manifest;
}

Manifest read_manifest(const std::string& path) { return read_manifest(ConfigNode::load_file(path), path); }

// The first key (a path such as "human.fingerprint") whose value differs, or "" if none.
std::string first_difference(const json& a, const json& b) {
  const json fa = a.flatten(), fb = b.flatten();
  for (const auto& item : fa.items()) {
    if (!fb.contains(item.key()) || fb[item.key()] != item.value()) return item.key();
  }
  for (const auto& item : fb.items()) {
    if (!fa.contains(item.key())) return item.key();
  }
  return "";
}

// "/human/fingerprint" (a JSON pointer) -> "human.fingerprint"
std::string dotted(std::string pointer) {
  if (!pointer.empty() && pointer[0] == '/') pointer.erase(0, 1);
  for (char& c : pointer) c = c == '/' ? '.' : c;
  return pointer;
}

void require_file(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw Error(path.string(), std::string("missing file (") + kFolderHint + ")");
}

// The file's SHA-256 against the manifest's; bundles of format 2 and later must list every file.
void verify_checksum(const fs::path& path, const Manifest& manifest, const std::string& manifest_file) {
  const std::string name = path.filename().string();
  const auto listed = manifest.sha256.find(name);
  if (listed == manifest.sha256.end()) {
    if (manifest.metadata.format_version >= 2)
      throw Error(manifest.sha256_where.empty() ? manifest_file : manifest.sha256_where,
                  "no SHA-256 of " + name + " (a bundle of format " + str(manifest.metadata.format_version) +
                      " lists every file's)");
    return;
  }
  const std::string actual = sha256_of_file(path.string());
  if (actual != listed->second)
    throw Error(path.string(), "its SHA-256 is " + actual + " but " + manifest_file + " says " + listed->second +
                                   ": the file was damaged or changed after export (export the bundle again)");
}

Mesh read_rest(const fs::path& path, const BundleSideMetadata& side, const std::string& label,
               const std::string& manifest) {
  require_file(path);
  Mesh rest = read_mesh(path.string());
  const std::string file = path.string();
  if (rest.vertex_count() != side.vertices) {
    throw Error(file, "has " + str(rest.vertex_count()) + " vertices but " + manifest + " says the " + label +
                          " topology has " + str(side.vertices));
  }
  if (rest.faces.size() != side.faces) {
    throw Error(file, "has " + str(rest.faces.size()) + " faces but " + manifest + " says the " + label +
                          " topology has " + str(side.faces));
  }
  const std::string fingerprint = topology_fingerprint(rest);
  if (fingerprint != side.fingerprint) {
    throw Error(file, "has the topology fingerprint " + fingerprint + " but " + manifest + " says " + side.fingerprint +
                          " (the " + label + " rest mesh does not belong to this bundle)");
  }
  return rest;
}

// rig.pt's offsets as the avatar's rig over `avatar_rest`.
Rig read_rig_file(const fs::path& path, const BundleRigMetadata& metadata, const Mesh& avatar_rest,
                  const BundleSideMetadata& avatar) {
  const std::string file = path.string();
  const TensorMap tensors = load_tensors(file);
  const torch::Tensor& offsets = tensor_named(tensors, kBundleRigOffsets, file);
  const auto c = static_cast<int64_t>(metadata.controllers.size());
  const int64_t v = avatar_rest.vertex_count();
  if (offsets.dim() != 3 || offsets.size(0) != c || offsets.size(1) != v || offsets.size(2) != 3)
    throw Error(file, "\"" + std::string(kBundleRigOffsets) + "\" has the shape " + str(offsets.sizes()) +
                          " but the manifest's rig has " + str(c) + " controllers over " + str(v) +
                          " avatar vertices: expected [" + str(c) + ", " + str(v) + ", 3]");
  if (!offsets.is_floating_point()) throw Error(file, "\"offsets\" should hold floating-point numbers");
  const torch::Tensor values = offsets.to(torch::kFloat64).contiguous();
  if (!torch::isfinite(values).all().item<bool>()) throw Error(file, "\"offsets\" holds values that are not finite");
  Rig rig;
  rig.name = avatar.name;
  rig.source = file;
  rig.units = avatar.units;
  rig.neutral = avatar_rest;
  const double* data = values.data_ptr<double>();
  for (int64_t k = 0; k < c; ++k) {
    Controller controller;
    controller.name = metadata.controllers[k].name;
    controller.min = metadata.controllers[k].min;
    controller.max = metadata.controllers[k].max;
    controller.offset = Eigen::Map<const Positions>(data + k * v * 3, v, 3);
    rig.controllers.push_back(std::move(controller));
  }
  return rig;
}

}  // namespace

void validate_bundle_rig(const BundleRigMetadata& rig, const std::string& where) {
  const auto [key, message] = rig_problem(rig);
  if (!key.empty()) throw Error(where + "." + key, message);
}

bool operator==(const BundleMetadata& a, const BundleMetadata& b) { return metadata_object(a) == metadata_object(b); }

void add_bundle_attributes(torch::jit::Module& module, const BundleMetadata& metadata) {
  const auto text = c10::StringType::get();
  const auto integer = c10::IntType::get();
  module.register_attribute("format", text, metadata.format);
  module.register_attribute("format_version", integer, metadata.format_version);
  module.register_attribute("software_version", text, metadata.software_version);
  module.register_attribute("created", text, metadata.created);
  module.register_attribute("features", integer, metadata.features);
  module.register_attribute("translation_hidden", integer, metadata.translation_hidden);
  add_side_attributes(module, metadata.human, "human_");
  add_side_attributes(module, metadata.avatar, "avatar_");
}

std::string bundle_manifest_text(const BundleMetadata& metadata, const std::map<std::string, std::string>& sha256) {
  return manifest_text(metadata, sha256);
}

BundleMetadata parse_bundle_manifest(const std::string& text, const std::string& name) {
  return read_manifest(ConfigNode::parse(text, name), name).metadata;
}

std::string bundle_metadata_json(const BundleMetadata& metadata) {
  json document = metadata_object(metadata);
  document["normalisation"] =
      fmt::format("normalise(x) = {} (x - normaliser_min) / (normaliser_max - normaliser_min) - {}",
                  2 * kNormalisedBound, kNormalisedBound);
  return document.dump(2) + "\n";
}

BundleMetadata parse_bundle_metadata_json(const std::string& text, const std::string& where) {
  const JsonFields fields{where, kBundleMetadataFile};
  const json document = fields.parse(text);
  if (document.value("format", json()) != kBundleFormat) {
    throw Error(where, std::string("not a retarget bundle: ") + kBundleMetadataFile + " has no \"format\": \"" +
                           kBundleFormat + "\"");
  }
  BundleMetadata m;
  m.format = kBundleFormat;
  m.format_version = fields.get<int64_t>(document, "format_version");
  if (m.format_version > kBundleFormatVersion) {
    throw Error(where, "written in bundle format " + str(m.format_version) +
                           " by a newer retarget; this build reads up to " + str(kBundleFormatVersion));
  }
  m.software_version = fields.get<std::string>(document, "software_version");
  m.created = fields.get<std::string>(document, "created");
  m.features = fields.get<int64_t>(document, "features");
  m.human = parse_side_json(fields, fields.member(document, "human"), "human");
  m.avatar = parse_side_json(fields, fields.member(document, "avatar"), "avatar");
  m.translation_hidden = fields.get<int64_t>(fields.member(document, "translation"), "hidden", "translation");
  if (document.contains("rig")) m.rig = parse_rig_json(fields, fields.member(document, "rig"));
  return m;
}

LoadedBundle load_bundle(const std::string& folder) {
  const fs::path dir(folder);
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw Error(folder, std::string("no such folder (") + kFolderHint + ")");
  const fs::path manifest_path = dir / kBundleManifestFile;
  require_file(manifest_path);
  const std::string manifest_file = manifest_path.string();
  const Manifest manifest = read_manifest(manifest_file);

  LoadedBundle bundle;
  bundle.folder = folder;
  bundle.metadata = manifest.metadata;
  const BundleMetadata& m = bundle.metadata;
  if (m.software_version != RETARGET_VERSION) {
    log::warn("{} was written by retarget {}; this is {}", manifest_file, m.software_version, RETARGET_VERSION);
  }

  const fs::path module_path = dir / manifest.module_file;
  const std::string module_file = module_path.string();
  require_file(module_path);
  if (manifest.sha256.empty())
    log::warn("{} lists no SHA-256 of the bundle's files (format {}); damage to them cannot be detected", manifest_file,
              m.format_version);
  std::vector<std::string> files{manifest.module_file, manifest.human_rest_file, manifest.avatar_rest_file};
  if (m.rig) files.push_back(manifest.rig_file);
  for (const std::string& file : files) require_file(dir / file);
  // The checksums are computed on a thread of their own while TorchScript reads the module (the
  // paper-size bundle.pt is 38 MB: hashing it took a third of retarget-infer's setup). A damaged
  // file is still reported by its checksum, before anything the load says about it.
  std::future<void> checked = std::async(std::launch::async, [&] {
    for (const std::string& file : files) verify_checksum(dir / file, manifest, manifest_file);
  });
  torch::jit::ExtraFilesMap extra{{kBundleMetadataFile, ""}};
  try {
    bundle.module = torch::jit::load(module_file, torch::Device(torch::kCPU), extra);
  } catch (const std::exception& e) {
    checked.get();
    throw Error(module_file, "cannot be read as a TorchScript module (truncated, or not a .pt file?): " +
                                 std::string(e.what()).substr(0, std::string(e.what()).find('\n')));
  }
  checked.get();
  const std::string& text = extra[kBundleMetadataFile];
  if (text.empty()) throw Error(module_file, "not a retarget bundle: it has no metadata.json");
  const BundleMetadata inside = parse_bundle_metadata_json(text, module_file);
  const std::string key = first_difference(metadata_object(inside), metadata_object(m));
  if (!key.empty()) {
    const json a = metadata_object(inside).flatten(), b = metadata_object(m).flatten();
    auto shown = [&key](const json& flat) { return flat.contains(key) ? flat[key].dump() : std::string("missing"); };
    throw Error(module_file, "does not belong with " + manifest_file + " (they come from different exports): \"" +
                                 dotted(key) + "\" is " + shown(a) + " here and " + shown(b) + " in the manifest");
  }
  for (const char* method : {"forward", "encode_human", "translate", "decode_avatar"}) {
    if (!bundle.module.find_method(method)) {
      throw Error(module_file, std::string("not a retarget bundle: it has no method ") + method + "()");
    }
  }
  bundle.module.eval();

  bundle.human_rest = read_rest(dir / manifest.human_rest_file, m.human, "human", manifest_file);
  bundle.avatar_rest = read_rest(dir / manifest.avatar_rest_file, m.avatar, "avatar", manifest_file);
  if (m.rig) bundle.rig = read_rig_file(dir / manifest.rig_file, *m.rig, bundle.avatar_rest, m.avatar);
  return bundle;
}

}  // namespace retarget
