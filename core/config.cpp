#include "core/config.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <utility>

#include "core/error.h"
#include "core/text_bytes.h"

namespace retarget {

namespace {

// "file:line: path" with the parts that are unknown left out.
std::string location(const std::string& file, const YAML::Mark& mark, const std::string& path) {
  std::string where = file;
  if (mark.line >= 0) where += fmt::format(":{}", mark.line + 1);
  if (!path.empty()) where += (where.empty() ? "" : ": ") + path;
  return where;
}

YAML::Mark mark_of(const YAML::Node& node) { return node.IsDefined() ? node.Mark() : YAML::Mark::null_mark(); }

enum class Parsed { ok, not_a_number, out_of_range };

// YAML 1.2 core-schema floats, locale-independent. Spellings strtod would also take
// ("inf", "nan", hex) are refused so a typo never reads as a number.
Parsed parse_double(const std::string& text, double& value) {
  std::string_view s = text;
  bool negative = false;
  if (!s.empty() && (s[0] == '+' || s[0] == '-')) {
    negative = s[0] == '-';
    s.remove_prefix(1);
  }
  if (s == ".inf" || s == ".Inf" || s == ".INF") {
    value = negative ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
    return Parsed::ok;
  }
  if (s == ".nan" || s == ".NaN" || s == ".NAN") {
    if (text.size() != s.size()) return Parsed::not_a_number;
    value = std::numeric_limits<double>::quiet_NaN();
    return Parsed::ok;
  }
  if (s.empty() || !(std::isdigit(static_cast<unsigned char>(s[0])) || s[0] == '.')) return Parsed::not_a_number;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value, std::chars_format::general);
  if (end != s.data() + s.size()) return Parsed::not_a_number;
  if (ec == std::errc::result_out_of_range) return Parsed::out_of_range;
  if (ec != std::errc()) return Parsed::not_a_number;
  if (negative) value = -value;
  return Parsed::ok;
}

// Integers; "1e5" and "3.0" are taken because people write them for counts, "2.5" is not.
Parsed parse_int64(const std::string& text, int64_t& value) {
  std::string_view s = text;
  if (s.size() > 1 && s[0] == '+' && std::isdigit(static_cast<unsigned char>(s[1]))) s.remove_prefix(1);
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (end == s.data() + s.size() && ec == std::errc()) return Parsed::ok;
  if (end == s.data() + s.size() && ec == std::errc::result_out_of_range) return Parsed::out_of_range;
  double d = 0;
  const Parsed parsed = parse_double(text, d);
  if (parsed != Parsed::ok) return parsed;
  if (std::isnan(d)) return Parsed::not_a_number;
  if (std::isfinite(d) && d != std::floor(d)) return Parsed::not_a_number;
  // Beyond 2^53 a double no longer holds every integer, so the value would not be exact.
  if (!(std::fabs(d) <= 9007199254740992.0)) return Parsed::out_of_range;
  value = static_cast<int64_t>(d);
  return Parsed::ok;
}

size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t substitute = diagonal + (std::tolower(static_cast<unsigned char>(a[i - 1])) !=
                                            std::tolower(static_cast<unsigned char>(b[j - 1])));
      diagonal = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, substitute});
    }
  }
  return row[b.size()];
}

// yaml-cpp keeps both entries of a duplicated key and lookups find the first, so a second
// value the user meant to take effect would be ignored without a word. Refuse them up front.
// Aliases make the document a graph (`&a [*a]` is a cycle, ten lists of ten aliases each a
// billion paths): each list or map is visited once, known by where its text starts.
void check_keys(const YAML::Node& node, const std::string& path, const std::string& file,
                std::set<std::pair<int, int>>& visited) {
  if (!node.IsSequence() && !node.IsMap()) return;
  if (!visited.emplace(node.Mark().line, node.Mark().column).second) return;
  if (node.IsSequence()) {
    for (size_t i = 0; i < node.size(); ++i) check_keys(node[i], fmt::format("{}[{}]", path, i), file, visited);
  } else {
    std::map<std::string, int> first_line;
    for (const auto& entry : node) {
      if (!entry.first.IsScalar())
        throw Error(location(file, entry.first.Mark(), path), "keys must be plain names, not lists or maps");
      const std::string key = entry.first.Scalar();
      const auto [it, inserted] = first_line.emplace(key, entry.first.Mark().line + 1);
      if (!inserted)
        throw Error(location(file, entry.first.Mark(), key_path(path, key)),
                    fmt::format("duplicate key (first given on line {})", it->second));
      check_keys(entry.second, key_path(path, key), file, visited);
    }
  }
}

}  // namespace

ConfigNode::ConfigNode(YAML::Node node, std::string path, std::string file)
    : node_(std::move(node)), path_(std::move(path)), file_(std::move(file)) {}

ConfigNode ConfigNode::parse(const std::string& text, const std::string& name) {
  if (text.size() > kMaxBytes)
    throw Error(name, fmt::format("{} bytes of YAML; a config is at most {} bytes (is this a config file?)",
                                  text.size(), kMaxBytes));
  require_text(text, name, "a config is YAML text");
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    std::string where = name;
    if (e.mark.line >= 0) where += fmt::format(":{}:{}", e.mark.line + 1, e.mark.column + 1);
    // yaml-cpp 0.7 stops at a nesting depth of about 500 with the message "bad file".
    if (e.msg == YAML::ErrorMsg::BAD_FILE)
      throw Error(where, "invalid YAML: nested too deeply for the YAML reader (a config is a few levels deep)");
    throw Error(where, "invalid YAML: " + e.msg);
  }
  std::set<std::pair<int, int>> visited;
  check_keys(root, "", name, visited);
  return ConfigNode(root, "", name);
}

ConfigNode ConfigNode::load_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw Error(path, "is a folder, not a config file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, std::string("cannot read config file: ") + std::strerror(errno));
  const uintmax_t bytes = std::filesystem::file_size(path, ec);
  if (!ec && bytes > kMaxBytes)
    throw Error(path, fmt::format("{} bytes; a config is at most {} bytes (is this a config file?)", bytes, kMaxBytes));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw Error(path, "cannot read config file: read failed");
  return parse(text.str(), path);
}

void ConfigNode::apply_override(const std::string& assignment) {
  const std::string where = "--set " + assignment;
  if (assignment.size() > kMaxBytes)
    throw Error("--set",
                fmt::format("{} bytes; a value is at most {} bytes, as a config is", assignment.size(), kMaxBytes));
  const size_t eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0) throw Error(where, "expected key.path=value");
  YAML::Node value;
  try {
    value = YAML::Load(assignment.substr(eq + 1));
  } catch (const YAML::Exception& e) {
    throw Error(where, "invalid YAML value: " + e.msg);
  }
  assign(assignment.substr(0, eq), value, where);
}

void ConfigNode::override_string(const std::string& key_path, const std::string& value, const std::string& source) {
  if (value.size() > kMaxBytes)
    throw Error(source, fmt::format("{} bytes; a value is at most {} bytes, as a config is", value.size(), kMaxBytes));
  assign(key_path, YAML::Node(value), source);
}

void ConfigNode::assign(const std::string& path, const YAML::Node& value, const std::string& source) {
  if (!node_.IsDefined() || node_.IsNull()) node_ = YAML::Node(YAML::NodeType::Map);
  YAML::Node current;
  current.reset(node_);
  std::string walked;
  size_t start = 0;
  while (true) {
    const size_t dot = path.find('.', start);
    const std::string key = path.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (key.empty()) throw Error(source, "empty key in '" + path + "'");
    if (!current.IsMap()) throw Error(source, "'" + walked + "' is not a map of keys");
    walked = key_path(walked, key);
    if (dot == std::string::npos) {
      current[key] = value;
      if (!overrides_) overrides_ = std::make_shared<std::map<std::string, std::string>>();
      // Earlier overrides inside the value just replaced no longer say where anything came from.
      for (auto it = overrides_->begin(); it != overrides_->end();) {
        const std::string& p = it->first;
        const bool inside =
            p.size() > walked.size() && p.rfind(walked, 0) == 0 && (p[walked.size()] == '.' || p[walked.size()] == '[');
        it = inside ? overrides_->erase(it) : std::next(it);
      }
      (*overrides_)[walked] = source;
      return;
    }
    if (!current[key].IsDefined() || current[key].IsNull()) current[key] = YAML::Node(YAML::NodeType::Map);
    YAML::Node next = current[key];
    current.reset(next);
    start = dot + 1;
  }
}

namespace {

// The entry of `sources` (key path -> where it came from) whose path is `path` or the nearest
// one above it ("a.b" holds "a.b.c" and "a.b[2]", not "a.bc"); nullptr if none.
const std::string* nearest_source(const std::map<std::string, std::string>* sources, const std::string& path) {
  if (!sources) return nullptr;
  const std::string* best = nullptr;
  size_t best_length = 0;
  for (const auto& [source_path, source] : *sources) {
    const bool under = path == source_path || (path.size() > source_path.size() && path.rfind(source_path, 0) == 0 &&
                                               (path[source_path.size()] == '.' || path[source_path.size()] == '['));
    if (under && (!best || source_path.size() >= best_length)) best = &source, best_length = source_path.size();
  }
  return best;
}

}  // namespace

std::string ConfigNode::source(const std::string& key_path) const {
  if (const std::string* set = nearest_source(overrides_.get(), key_path)) return *set;
  if (const std::string* file = nearest_source(origins_.get(), key_path)) return *file;
  return file_;
}

std::string ConfigNode::place(const std::string& path, const YAML::Mark& mark) const {
  if (const std::string* set = nearest_source(overrides_.get(), path)) return *set + ": " + path;
  const std::string* file = nearest_source(origins_.get(), path);
  return location(file ? *file : file_, mark, path);
}

std::string ConfigNode::where() const { return place(path_, mark_of(node_)); }

void ConfigNode::fail(const std::string& message) const { throw Error(where(), message); }

void ConfigNode::expect_map() const {
  if (!is_null() && !node_.IsMap()) fail("expected a map of keys, got " + describe());
}

bool ConfigNode::has(const std::string& key) const {
  expect_map();
  return !is_null() && node_[key].IsDefined();
}

ConfigNode ConfigNode::child(const std::string& key) const {
  if (!has(key)) throw Error(location(file_, YAML::Mark::null_mark(), key_path(path_, key)), "missing required key");
  ConfigNode node(node_[key], key_path(path_, key), file_);
  node.overrides_ = overrides_;
  node.origins_ = origins_;
  return node;
}

ConfigNode ConfigNode::at(size_t i) const {
  if (!node_.IsSequence()) fail("expected a list, got " + describe());
  if (i >= node_.size()) fail(fmt::format("expected at least {} items, got {}", i + 1, node_.size()));
  ConfigNode node(node_[i], fmt::format("{}[{}]", path_, i), file_);
  node.overrides_ = overrides_;
  node.origins_ = origins_;
  return node;
}

size_t ConfigNode::size() const {
  if (is_null()) return 0;
  if (node_.IsScalar()) fail("expected a list or a map, got " + describe());
  return node_.size();
}

std::string ConfigNode::describe() const {
  if (is_null()) return "nothing";
  if (node_.IsMap()) return "a map";
  if (node_.IsSequence()) return "a list";
  std::string text = node_.Scalar();
  double unused = 0;
  // A plain (unquoted) number is shown as written; anything else in quotes, so that an empty
  // or blank value is still visible.
  if (node_.Tag() != "!" && parse_double(text, unused) != Parsed::not_a_number) return text;
  if (text.size() > 40) text = text.substr(0, 37) + "...";
  return "\"" + text + "\"";
}

double ConfigNode::read(double*) const {
  double value = 0;
  const Parsed parsed = node_.IsScalar() ? parse_double(node_.Scalar(), value) : Parsed::not_a_number;
  if (parsed == Parsed::out_of_range) fail("expected a number within the range of a double, got " + describe());
  if (parsed != Parsed::ok) fail("expected a number, got " + describe());
  return value;
}

float ConfigNode::read(float*) const {
  const double value = as<double>();
  constexpr double largest = std::numeric_limits<float>::max();
  if (std::isfinite(value) && std::fabs(value) > largest)
    fail(fmt::format("expected a number between {} and {}, got {}", -largest, largest, describe()));
  return static_cast<float>(value);
}

int64_t ConfigNode::read_integer(int64_t lo, int64_t hi) const {
  int64_t value = 0;
  const Parsed parsed = node_.IsScalar() ? parse_int64(node_.Scalar(), value) : Parsed::not_a_number;
  if (parsed == Parsed::out_of_range || (parsed == Parsed::ok && (value < lo || value > hi)))
    fail(fmt::format("expected an integer between {} and {}, got {}", lo, hi, describe()));
  if (parsed != Parsed::ok) fail("expected an integer, got " + describe());
  return value;
}

int64_t ConfigNode::read(int64_t*) const {
  return read_integer(std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::max());
}

int ConfigNode::read(int*) const {
  return static_cast<int>(read_integer(std::numeric_limits<int>::min(), std::numeric_limits<int>::max()));
}

bool ConfigNode::read(bool*) const {
  if (node_.IsScalar() && node_.Scalar() == "true") return true;
  if (node_.IsScalar() && node_.Scalar() == "false") return false;
  fail("expected true or false, got " + describe());
}

std::string ConfigNode::read(std::string*) const {
  if (is_null() || !node_.IsScalar()) fail("expected a string, got " + describe());
  return node_.Scalar();
}

void ConfigNode::reject_unknown_keys(std::initializer_list<const char*> known) const {
  reject_unknown_keys(std::vector<std::string>(known.begin(), known.end()));
}

void ConfigNode::reject_unknown_keys(const std::vector<std::string>& known) const {
  expect_map();
  if (is_null()) return;
  for (const auto& entry : node_) {
    const std::string key = entry.first.Scalar();
    if (std::find(known.begin(), known.end(), key) != known.end()) continue;
    const std::string where = place(key_path(path_, key), entry.first.Mark());
    const std::string* closest = nullptr;
    size_t best = std::numeric_limits<size_t>::max();
    for (const std::string& candidate : known) {
      const size_t distance = edit_distance(key, candidate);
      if (distance < best) best = distance, closest = &candidate;
    }
    // Only a near miss is worth suggesting; otherwise list what the section takes.
    if (closest && best <= std::max<size_t>(1, closest->size() / 3))
      throw Error(where, fmt::format("unknown key (did you mean '{}'?)", *closest));
    if (known.empty()) throw Error(where, "unknown key (this section takes no keys)");
    throw Error(where, fmt::format("unknown key (known keys: {})", fmt::join(known, ", ")));
  }
}

std::string key_path(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}

void require(bool condition, const std::string& key_path, const std::string& message) {
  if (!condition) throw Error(key_path, message);
}

void require_positive(double value, const std::string& key_path) {
  require(value > 0, key_path, fmt::format("expected a positive number, got {}", value));
}

void require_non_negative(double value, const std::string& key_path) {
  require(value >= 0, key_path, fmt::format("expected a number >= 0, got {}", value));
}

void require_in_range(double value, double lo, double hi, const std::string& key_path) {
  require(value >= lo && value <= hi, key_path, fmt::format("expected a number in [{}, {}], got {}", lo, hi, value));
}

}  // namespace retarget
