#include "train/train_config.h"

#include <torch/torch.h>

#include "core/config_base.h"
#include "core/cpu_threads.h"

namespace retarget {

std::string config_task(const ConfigNode& root) {
  const ConfigNode task = root.child("task");
  const std::string name = task.as<std::string>();
  if (name != "vae" && name != "translation" && name != "cyclegan")
    task.fail("unknown task '" + name + "' (known: vae, translation, cyclegan)");
  return name;
}

ConfigNode load_config_with_overrides(const std::string& path, const std::vector<std::string>& overrides) {
  ConfigNode root = load_config_with_bases(path);
  for (const std::string& assignment : overrides) root.apply_override(assignment);
  return root;
}

void read_run_path(const ConfigNode& section, const std::string& key, const std::string& what, std::string& value) {
  if (!section.has(key)) {
    const std::string path = key_path(section.path(), key);
    throw Error(section.file() + ": " + path, "missing: " + what + "; give it with --set " + path +
                                                  "=PATH (the profiles under configs/train name no run's files)");
  }
  section.get_required(key, value);
}

void read_output(const ConfigNode& root, std::string& output) {
  if (!root.has("output"))
    throw Error(root.file() + ": output",
                "missing: the run folder; give it with `retarget train CONFIG --out DIR` (or --set output=DIR)");
  root.get_required("output", output);
}

namespace {

// The node at `path` ("stages[2].weights.group") below `root`; false if the document has none.
bool node_at(const ConfigNode& root, const std::string& path, ConfigNode& node) {
  if (path.empty()) return false;
  try {
    node = root;
    size_t at = 0;
    while (at < path.size()) {
      if (path[at] == '[') {
        const size_t close = path.find(']', at);
        if (close == std::string::npos || !node.is_sequence()) return false;
        const size_t index = std::stoul(path.substr(at + 1, close - at - 1));
        if (index >= node.size()) return false;
        node = node.at(index);
        at = close + 1;
      } else {
        if (path[at] == '.') ++at;
        const size_t end = path.find_first_of(".[", at);
        const std::string key = path.substr(at, end == std::string::npos ? std::string::npos : end - at);
        if (key.empty() || !node.is_map() || !node.has(key)) return false;
        node = node.child(key);
        at = end == std::string::npos ? path.size() : end;
      }
    }
    return true;
  } catch (const std::exception&) {  // not a key path of this document
    return false;
  }
}

}  // namespace

void rethrow_with_source(const ConfigNode& root, const Error& e) {
  ConfigNode node;
  if (node_at(root, e.where(), node)) throw Error(node.where(), e.detail());
  throw Error(root.source(e.where()) + ": " + e.where(), e.detail());
}

void read_seed(const ConfigNode& node, const std::string& key, uint64_t& seed) {
  if (!node.has(key)) return;
  const int64_t value = node.child(key).as<int64_t>();
  if (value < 0) node.child(key).fail("expected a number >= 0, got " + std::to_string(value));
  seed = static_cast<uint64_t>(value);
}

void TrainingLoopOptions::validate(const std::string& key_path) const {
  require_positive(batch_size, retarget::key_path(key_path, "batch_size"));
  require_positive(checkpoint_every, retarget::key_path(key_path, "checkpoint_every"));
  require_non_negative(threads, retarget::key_path(key_path, "threads"));
}

void read_training_loop(const ConfigNode& training, const std::vector<std::string>& own_keys,
                        TrainingLoopOptions& options) {
  std::vector<std::string> known = own_keys;
  known.insert(known.end(), {"batch_size", "checkpoint_every", "seed", "threads"});
  training.reject_unknown_keys(known);
  training.get("batch_size", options.batch_size);
  training.get("checkpoint_every", options.checkpoint_every);
  read_seed(training, "seed", options.seed);
  training.get("threads", options.threads);
}

void write_training_loop(YAML::Node training, const TrainingLoopOptions& options) {
  training["batch_size"] = options.batch_size;
  training["checkpoint_every"] = options.checkpoint_every;
  training["seed"] = options.seed;
  training["threads"] = options.threads;
}

YAML::Node flow_style(YAML::Node node) {
  node.SetStyle(YAML::EmitterStyle::Flow);
  return node;
}

std::string config_yaml_text(const YAML::Node& root) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << root;
  return std::string(out.c_str()) + "\n";
}

int use_training_threads(int configured) {
  const int threads = checked_thread_count(configured, "training.threads");
  torch::set_num_threads(threads);
  return threads;
}

}  // namespace retarget
