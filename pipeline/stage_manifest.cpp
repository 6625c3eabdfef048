#include "pipeline/stage_manifest.h"

#include <filesystem>

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"

namespace fs = std::filesystem;

namespace retarget {

std::string stage_manifest_path(const std::string& run, const std::string& key) {
  return (fs::path(run) / "pipeline" / (key + ".yaml")).string();
}

std::optional<StageManifest> load_stage_manifest(const std::string& path) {
  if (!fs::exists(path)) return std::nullopt;
  const ConfigNode node = ConfigNode::load_file(path);
  StageManifest m;
  node.get_required("key", m.key);
  node.get_required("fingerprint", m.fingerprint);
  node.get_required("status", m.status);
  node.get("started", m.started);
  node.get("finished", m.finished);
  node.get("seconds", m.seconds);
  node.get("commands", m.commands);
  node.get("inputs", m.inputs);
  if (m.status != "running" && m.status != "finished")
    node.child("status").fail("expected running or finished, got \"" + m.status + "\"");
  return m;
}

void save_stage_manifest(const std::string& path, const StageManifest& m) {
  fs::create_directories(fs::path(path).parent_path());
  YAML::Emitter y;
  y << YAML::BeginMap;
  y << YAML::Key << "key" << YAML::Value << m.key;
  y << YAML::Key << "fingerprint" << YAML::Value << m.fingerprint;
  y << YAML::Key << "status" << YAML::Value << m.status;
  y << YAML::Key << "started" << YAML::Value << m.started;
  y << YAML::Key << "finished" << YAML::Value << m.finished;
  y << YAML::Key << "seconds" << YAML::Value << m.seconds;
  y << YAML::Key << "commands" << YAML::Value << YAML::BeginSeq;
  for (const std::string& c : m.commands) y << c;
  y << YAML::EndSeq;
  y << YAML::Key << "inputs" << YAML::Value << YAML::BeginSeq;
  for (const std::string& i : m.inputs) y << i;
  y << YAML::EndSeq;
  y << YAML::EndMap;
  const std::string text = std::string(y.c_str()) + "\n";
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

}  // namespace retarget
