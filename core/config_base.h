// A config file built on another: its `base:` key names a config (a path relative to the file
// that names it) whose keys it is merged over, so that a profile states only what it changes.
//
//   # configs/train/quick/avatar_vae.yaml
//   base: ../avatar_vae.yaml          # the paper's settings
//   model:
//     channels: [9, 32, 16, 16, 16, 1]
//   training:
//     epochs: 10
//
// Maps merge key by key, recursively; lists and scalars in the file replace the base's whole (a
// list of stages is restated, not patched). A key written without a value over a base's map keeps
// that map (as a section whose keys are all commented out keeps its defaults); over anything else
// it is null. A base may have a base of its own. Messages about a value name the file it came
// from, with its line: "configs/train/avatar_vae.yaml:18: optimiser.lr: ...".
#pragma once

#include <string>
#include <vector>

#include "core/config.h"

namespace retarget {

// Reads the YAML config at `path` (ConfigNode::load_file) and, when its root is a map with a
// `base:` key, the chain of bases it names, and returns the merged document without `base:`.
// file() is `path`; source(key_path) names the file each value came from. Throws
// retarget::Error naming the file and line of the `base:` key and the chain so far
// ("quick/a.yaml:1: base: ../b.yaml: no such file (.../b.yaml); chain: quick/a.yaml -> ../b.yaml")
// for a base that is not a non-empty string, a missing or unreadable base, a base whose document
// is not a map, and a cycle; a base's own syntax and key errors name that base.
ConfigNode load_config_with_bases(const std::string& path);

// The files the config at `path` is made of: itself, then its base, its base's base..., each as
// an absolute path (what a run's result depends on, for fingerprints). Throws as
// load_config_with_bases does.
std::vector<std::string> config_chain_files(const std::string& path);

}  // namespace retarget
