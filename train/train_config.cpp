#include "train/train_config.h"

#include <torch/torch.h>

#include "core/cpu_threads.h"

namespace retarget {

std::string config_task(const ConfigNode& root) {
  const ConfigNode task = root.child("task");
  const std::string name = task.as<std::string>();
  if (name != "vae" && name != "translation") task.fail("unknown task '" + name + "' (known: vae, translation)");
  return name;
}

ConfigNode load_config_with_overrides(const std::string& path, const std::vector<std::string>& overrides) {
  ConfigNode root = ConfigNode::load_file(path);
  for (const std::string& assignment : overrides) root.apply_override(assignment);
  return root;
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
