// YAML configuration read into options structs. Every error names the file, the line and the
// key path (`config.yaml:12: translation.stages[2].lr: expected a number, got "fast"`), so a
// user can fix the file without reading code.
//
// The pattern for an options struct: defaults live in the struct, the loader maps keys one to
// one and then calls validate():
//
//   StageOptions read_stage(const ConfigNode& node) {
//     node.reject_unknown_keys({"lr", "epochs"});
//     StageOptions options;
//     node.get("lr", options.lr);
//     node.get("epochs", options.epochs);
//     options.validate(node.path());
//     return options;
//   }
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace retarget {

// One node of a parsed YAML document together with where it came from. Cheap to copy.
// A null node (a key written without a value, or an empty document) reads as an empty map,
// so a section whose keys are all commented out keeps its defaults.
class ConfigNode {
 public:
  ConfigNode() = default;

  // A config file (or text) is at most this long: configs are a few KB, and yaml-cpp takes
  // about 130 bytes of memory per byte of YAML.
  static constexpr size_t kMaxBytes = size_t{1} << 20;

  // Reads and parses a YAML file. Throws retarget::Error naming the file if it cannot be
  // read or is over kMaxBytes (before reading it), and "file:line:column" for a syntax error,
  // nesting too deep for the parser, or a duplicate key.
  static ConfigNode load_file(const std::string& path);
  // Parses YAML text; `name` stands for the file in messages. The same errors.
  static ConfigNode parse(const std::string& text, const std::string& name);

  // True if this map holds `key`. Throws if this node is a scalar or a list.
  bool has(const std::string& key) const;
  // The value under `key`. Throws "<path>.<key>: missing required key" if absent.
  ConfigNode child(const std::string& key) const;
  // Item i of a list. Throws if this is not a list or i is out of range.
  ConfigNode at(size_t i) const;
  // Items of a list or entries of a map; 0 for null. Throws for a scalar.
  size_t size() const;

  bool is_map() const { return node_.IsMap(); }
  bool is_sequence() const { return node_.IsSequence(); }
  bool is_null() const { return !node_.IsDefined() || node_.IsNull(); }

  // The value converted to T: double, float, int, int64_t, bool (true/false only),
  // std::string, or std::vector of any of these (nested vectors too). Integers reject
  // fractions and out-of-range values. Throws retarget::Error naming the key path and line.
  template <typename T>
  T as() const {
    return read(static_cast<T*>(nullptr));
  }

  // Sets `value` from `key` when the key is present; otherwise leaves the default in place.
  // A key written without a value is an error, not a request for the default.
  template <typename T>
  void get(const std::string& key, T& value) const {
    if (has(key)) value = child(key).as<T>();
  }
  // Sets `value` from `key`; throws if the key is missing.
  template <typename T>
  void get_required(const std::string& key, T& value) const {
    value = child(key).as<T>();
  }

  // Throws for the first key of this map not in `known`, suggesting the closest known key:
  // "model.laten_size: unknown key (did you mean 'latent_size'?)".
  void reject_unknown_keys(std::initializer_list<const char*> known) const;
  void reject_unknown_keys(const std::vector<std::string>& known) const;

  // The key path ("translation.stages[2].lr"; empty for the document root).
  const std::string& path() const { return path_; }
  // The file name given to load_file() or parse().
  const std::string& file() const { return file_; }
  // "file:line: path", the `where` of errors about this node (line omitted if unknown).
  std::string where() const;
  // Throws retarget::Error(where(), message), for checks only the caller knows about.
  [[noreturn]] void fail(const std::string& message) const;

  const YAML::Node& yaml() const { return node_; }

  // Applies a command-line override "a.b.c=value" to this document (call it on the root):
  // the value is read as YAML ("3", "1e-4", "[9, 32, 1]", "text"); maps missing on the path
  // are created. Throws retarget::Error("--set <assignment>", ...) for a malformed assignment
  // or a path that runs through a scalar or a list. Errors about an overridden value (or a
  // value inside it) name the override and the key path: "--set model.latent=-1: model.latent".
  void apply_override(const std::string& assignment);
  // Sets the value at `key_path` ("a.b.c") to the string `value` as it is, not read as YAML (a
  // folder from a command-line option such as `--out DIR`), as apply_override would; `source`
  // ("--out DIR") names it in errors about the value or the path.
  void override_string(const std::string& key_path, const std::string& value, const std::string& source);

  // Where the value at `key_path` (from the document's root) came from, for messages: the
  // override that set it ("--set a.b=1"), else the file that holds it: a base file for values
  // a merged config (core/config_base.h) took from there, file() otherwise.
  std::string source(const std::string& key_path) const;

 private:
  ConfigNode(YAML::Node node, std::string path, std::string file);
  // The merged document of a config built on bases: `origins` maps key paths to the file each
  // subtree came from (paths not in it, and not below one, came from `file`).
  friend ConfigNode load_config_with_bases(const std::string& path);
  // Sets the value at `path` ("a.b.c") to `value`, creating missing maps; `source` names it.
  void assign(const std::string& path, const YAML::Node& value, const std::string& source);
  void expect_map() const;

  int64_t read_integer(int64_t lo, int64_t hi) const;
  double read(double*) const;
  float read(float*) const;
  int read(int*) const;
  int64_t read(int64_t*) const;
  bool read(bool*) const;
  std::string read(std::string*) const;
  template <typename T>
  std::vector<T> read(std::vector<T>*) const {
    if (!node_.IsSequence()) fail("expected a list, got " + describe());
    std::vector<T> values;
    values.reserve(node_.size());
    for (size_t i = 0; i < node_.size(); ++i) values.push_back(at(i).as<T>());
    return values;
  }
  // The value as a message shows it: `"fast"`, `2.5`, `a map`, `nothing`.
  std::string describe() const;

  // Where a value at `path` (its text at `mark`) came from, for messages: "--set a.b=v: path"
  // when it lies under an override, else "file:line: path" with the file source() names.
  std::string place(const std::string& path, const YAML::Mark& mark) const;

  YAML::Node node_;
  std::string path_;
  std::string file_;
  // Key path -> the override that set it ("--set a.b=1", "--out DIR"); shared by every node
  // read from one root.
  std::shared_ptr<std::map<std::string, std::string>> overrides_;
  // Key path -> the base file its value came from, in a merged config (core/config_base.h).
  std::shared_ptr<const std::map<std::string, std::string>> origins_;
};

// "parent.key", or "key" when parent is the root (empty).
std::string key_path(const std::string& parent, const std::string& key);

// Checks for options structs' validate() methods. Each throws retarget::Error(key_path, ...).
void require(bool condition, const std::string& key_path, const std::string& message);
// "expected a positive number, got -1"
void require_positive(double value, const std::string& key_path);
// "expected a number >= 0, got -1"
void require_non_negative(double value, const std::string& key_path);
// "expected a number in [lo, hi], got v" (both ends inclusive)
void require_in_range(double value, double lo, double hi, const std::string& key_path);

}  // namespace retarget
