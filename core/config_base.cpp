#include "core/config_base.h"

#include <fmt/format.h>

#include <filesystem>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "core/error.h"

namespace retarget {

namespace fs = std::filesystem;

namespace {

// One file of a chain after its own bases were merged into it.
struct MergedFile {
  YAML::Node root;
  std::string file;
  std::map<std::string, std::string> origins;  // key path -> the base file it came from
};

// "a.yaml -> b.yaml -> c.yaml"
std::string chain_text(const std::vector<std::string>& chain) {
  std::string text;
  for (const std::string& file : chain) text += (text.empty() ? "" : " -> ") + file;
  return text;
}

// True if `path` is `above` or lies below it ("a.b" holds "a.b.c" and "a.b[2]", not "a.bc").
bool at_or_below(const std::string& path, const std::string& above) {
  return path == above || (path.size() > above.size() && path.rfind(above, 0) == 0 &&
                           (path[above.size()] == '.' || path[above.size()] == '['));
}

// The file the value at `path` of `merged` came from: its nearest origin, else its own file.
std::string origin_of(const MergedFile& merged, const std::string& path) {
  const std::string* best = &merged.file;
  size_t best_length = 0;
  for (const auto& [origin_path, file] : merged.origins)
    if (at_or_below(path, origin_path) && origin_path.size() >= best_length)
      best = &file, best_length = origin_path.size();
  return *best;
}

// The value of `key` in the map `node`; an undefined node if absent (looked up without
// inserting, as a non-const operator[] would).
YAML::Node value_of(const YAML::Node& node, const std::string& key) {
  for (auto entry = node.begin(); entry != node.end(); ++entry)
    if (entry->first.Scalar() == key) return entry->second;
  return YAML::Node(YAML::NodeType::Undefined);
}

// Merges the map `base` (at key path `path` of `from`) into the map `overlay`, in place: keys the
// overlay lacks are taken from the base, with their marks, and recorded in `origins`.
void merge_maps(YAML::Node overlay, const YAML::Node& base, const std::string& path, const MergedFile& from,
                std::map<std::string, std::string>& origins) {
  const auto take = [&](const std::string& taken) {
    origins[taken] = origin_of(from, taken);
    for (const auto& [origin_path, file] : from.origins)
      if (origin_path != taken && at_or_below(origin_path, taken)) origins[origin_path] = file;
  };
  for (auto entry = base.begin(); entry != base.end(); ++entry) {
    const std::string child = key_path(path, entry->first.Scalar());
    YAML::Node mine = value_of(overlay, entry->first.Scalar());
    if (!mine.IsDefined()) {
      overlay.force_insert(entry->first, entry->second);
      take(child);
    } else if (entry->second.IsMap() && mine.IsMap()) {
      merge_maps(mine, entry->second, child, from, origins);
    } else if (entry->second.IsMap() && mine.IsNull()) {
      mine = entry->second;  // the overlay's entry now refers to the base's map
      take(child);
    }
    // Otherwise the overlay's scalar, list or null replaces the base's value whole.
  }
}

MergedFile load_chain(const std::string& path, std::vector<std::string> chain, std::vector<fs::path>& canonical) {
  const ConfigNode root = ConfigNode::load_file(path);
  chain.push_back(path);
  MergedFile merged{root.yaml(), path, {}};
  if (!root.is_map() || !root.has("base")) return merged;

  const ConfigNode base_node = root.child("base");
  // Messages point at the key's line: a value left empty is marked on the line after it.
  std::string where = "base";
  for (auto entry = root.yaml().begin(); entry != root.yaml().end(); ++entry)
    if (entry->first.Scalar() == "base") where = fmt::format("{}:{}: base", path, entry->first.Mark().line + 1);
  if (base_node.is_null() || base_node.is_map() || base_node.is_sequence())
    throw Error(where, "expected the path of a config file (relative to this one)");
  const std::string base_name = base_node.as<std::string>();
  if (base_name.empty()) throw Error(where, "expected the path of a config file (relative to this one), got \"\"");
  const fs::path base_path = (fs::path(path).parent_path() / base_name).lexically_normal();
  const std::string base_file = base_path.string();
  std::vector<std::string> next = chain;
  next.push_back(base_file);

  std::error_code ec;
  const fs::path resolved = fs::weakly_canonical(base_path, ec);
  for (const fs::path& seen : canonical)
    if (!ec && resolved == seen) throw Error(where, base_name + ": a cycle of bases: " + chain_text(next));
  if (!fs::exists(base_path, ec))
    throw Error(where, fmt::format("{}: no such file ({}); chain: {}", base_name, base_file, chain_text(next)));
  if (!fs::is_regular_file(base_path, ec))
    throw Error(where, fmt::format("{}: not a file ({}); chain: {}", base_name, base_file, chain_text(next)));
  canonical.push_back(resolved);

  MergedFile base = load_chain(base_file, chain, canonical);
  if (!base.root.IsMap())
    throw Error(base_file, fmt::format("a base config must be a map of keys, and this document is {}; chain: {}",
                                       base.root.IsSequence() ? "a list"
                                       : base.root.IsScalar() ? "a single value"
                                                              : "empty",
                                       chain_text(next)));
  merged.root.remove("base");
  merge_maps(merged.root, base.root, "", base, merged.origins);
  return merged;
}

}  // namespace

ConfigNode load_config_with_bases(const std::string& path) {
  std::vector<fs::path> canonical;
  std::error_code ec;
  canonical.push_back(fs::weakly_canonical(path, ec));
  MergedFile merged = load_chain(path, {}, canonical);
  ConfigNode node(merged.root, "", path);
  if (!merged.origins.empty())
    node.origins_ = std::make_shared<const std::map<std::string, std::string>>(std::move(merged.origins));
  return node;
}

std::vector<std::string> config_chain_files(const std::string& path) {
  std::vector<fs::path> canonical;
  std::error_code ec;
  canonical.push_back(fs::weakly_canonical(path, ec));
  load_chain(path, {}, canonical);
  std::vector<std::string> files;
  for (const fs::path& file : canonical) files.push_back(file.string());
  return files;
}

}  // namespace retarget
