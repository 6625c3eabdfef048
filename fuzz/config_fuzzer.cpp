// libFuzzer target: YAML text through ConfigNode (core/config.h): parse, an override taken from
// the first line ("a.b=value"), then every node read as each type the loaders ask for and every
// map checked for unknown keys.
#include <string>
#include <vector>

#include "core/config.h"
#include "core/error.h"
#include "fuzz/fuzz_input.h"

namespace {

template <typename T>
void try_as(const retarget::ConfigNode& node) {
  try {
    (void)node.as<T>();
  } catch (const retarget::Error&) {
  }
}

// Aliases make the document a graph with exponentially many paths: the harness visits at most
// `budget` nodes so that its own walk stays linear (the library's checks visit each node once).
void visit(const retarget::ConfigNode& node, int depth, int& budget) {
  if (depth > 64 || --budget < 0) return;
  try_as<double>(node);
  try_as<float>(node);
  try_as<int>(node);
  try_as<int64_t>(node);
  try_as<bool>(node);
  try_as<std::string>(node);
  try_as<std::vector<double>>(node);
  try_as<std::vector<std::vector<int>>>(node);
  try_as<std::vector<std::string>>(node);
  try {
    node.reject_unknown_keys({"name", "lr", "epochs", "stages", "model", "latent_size"});
  } catch (const retarget::Error&) {
  }
  try {
    if (node.is_map()) {
      for (const auto& entry : node.yaml()) {
        const std::string key = entry.first.IsScalar() ? entry.first.Scalar() : std::string();
        if (!key.empty() && node.has(key)) visit(node.child(key), depth + 1, budget);
      }
    } else if (node.is_sequence()) {
      for (size_t i = 0; i < node.size(); ++i) visit(node.at(i), depth + 1, budget);
    }
  } catch (const retarget::Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(retarget::fuzz::bytes(data, size));
  const size_t newline = text.find('\n');
  try {
    retarget::ConfigNode root = retarget::ConfigNode::parse(text, "fuzz.yaml");
    if (newline != std::string::npos && text.find('=') < newline) {
      try {
        root.apply_override(text.substr(0, newline));
      } catch (const retarget::Error&) {
      }
    }
    int budget = 2000;
    visit(root, 0, budget);
  } catch (const retarget::Error&) {
  }
  return 0;
}
