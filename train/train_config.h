// What every training config (`retarget train CONFIG`) shares, whatever its `task:`: reading
// the task, the file with --set overrides, the seed, writing a config back as YAML, and the
// thread count a run uses. The task's own keys live in train/vae_config.h and
// translate/translation_config.h.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/error.h"

namespace retarget {

// The `training:` keys every trainer has. Each task's options derive from this and set their
// own defaults (train/vae_config.h, translate/translation_config.h).
struct TrainingLoopOptions {
  int batch_size = 32;
  int checkpoint_every = 1;  // epochs between checkpoints (the last epoch always writes one)
  uint64_t seed = 1;         // initialisation, batch order and every other random choice of the run
  int threads = 0;           // LibTorch intra-op threads; 0: all cores
  // Throws retarget::Error naming key_path.batch_size etc.
  void validate(const std::string& key_path = "training") const;
};

// Reads the shared keys from a `training:` node into `options`; `own_keys` are the task's other
// keys there (the caller reads them), any further key is rejected with its closest match.
void read_training_loop(const ConfigNode& training, const std::vector<std::string>& own_keys,
                        TrainingLoopOptions& options);
// Writes the shared keys into a `training:` map.
void write_training_loop(YAML::Node training, const TrainingLoopOptions& options);

// Reads a key that names one run's files (data.dataset, data.human_vae, ...) into `value`. The
// profiles under configs/train name none, so a missing one is an error saying how to give it:
// "c.yaml: data.dataset: missing: the dataset folder; give it with --set data.dataset=DIR".
// `what`: "the dataset folder".
void read_run_path(const ConfigNode& section, const std::string& key, const std::string& what, std::string& value);

// Re-throws an options struct's validate() error (a key path, no file) at the value it names:
// "file:line: key.path" with the file the value came from (a base's for a value taken from it),
// or "--set a.b=1: key.path"; the file alone when the document has no value there.
[[noreturn]] void rethrow_with_source(const ConfigNode& root, const Error& e);

// Runs `validate` (an options struct's validate() with its section's key path, "optimiser") and
// re-throws its error with rethrow_with_source.
template <typename Validate>
void validate_in(const ConfigNode& root, const Validate& validate) {
  try {
    validate();
  } catch (const Error& e) {
    rethrow_with_source(root, e);
  }
}

// Reads the required `output` (the run folder); a missing one says to give it with `retarget
// train --out DIR` (or --set output=DIR).
void read_output(const ConfigNode& root, std::string& output);

// The end of every config reader: read_output, then config.validate() through validate_in.
template <typename Config>
Config finish_train_config(const ConfigNode& root, Config config) {
  read_output(root, config.output);
  validate_in(root, [&] { config.validate(); });
  return config;
}

// The `task:` of a training config: "vae", "translation" or "cyclegan". Throws retarget::Error naming the
// key if missing or unknown.
std::string config_task(const ConfigNode& root);

// Reads a config file with its chain of bases merged (core/config_base.h), then applies
// "key.path=value" overrides (ConfigNode::apply_override) in order.
ConfigNode load_config_with_overrides(const std::string& path, const std::vector<std::string>& overrides);

// Sets `seed` from node[key] when present: an integer >= 0 (YAML integers are signed).
void read_seed(const ConfigNode& node, const std::string& key, uint64_t& seed);

// A YAML list written on one line ([9, 128, 1]).
YAML::Node flow_style(YAML::Node node);
// A config document as text, doubles with full precision (so a run's config.yaml reads back to
// the same values), ending in a newline.
std::string config_yaml_text(const YAML::Node& root);

// Sets LibTorch's intra-op threads for a run: `configured` if > 0, else default_thread_count()
// (core/cpu_threads.h: OMP_NUM_THREADS, which torchrun and --nproc set for their workers, or
// every core). Returns the number used.
int use_training_threads(int configured);

}  // namespace retarget
