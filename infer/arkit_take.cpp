#include "infer/arkit_take.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <string_view>

#include "core/error.h"
#include "core/log.h"
#include "core/text_bytes.h"
#include "geometry/text_lines.h"

namespace retarget {

// Named, not anonymous: ArkitRowParser::State holds these types (a class with linkage must not
// hold anonymous-namespace types), and the using-directive below gives them to the file as an
// anonymous namespace would.
namespace arkit_take_detail {

namespace fs = std::filesystem;
using TakeJson = nlohmann::ordered_json;

std::string lowercase(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

bool ends_with(const std::string& text, std::string_view suffix) {
  return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

bool is_separator(char c) { return c == '_' || c == '-' || c == '.' || c == ' '; }

std::string_view trim_space(std::string_view text) {
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front()))) text.remove_prefix(1);
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.remove_suffix(1);
  return text;
}

// A field without blanks around it and without the double quotes some writers wrap text in.
std::string_view unquote(std::string_view field) {
  field = trim_space(field);
  if (field.size() >= 2 && field.front() == '"' && field.back() == '"')
    field = trim_space(field.substr(1, field.size() - 2));
  return field;
}

std::string comma_list(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& name : names) out += (out.empty() ? "" : ", ") + name;
  return out;
}

// Which expressions each take name drives, and which name drives each expression (a second
// name for one expression is an error).
class NameMatcher {
 public:
  explicit NameMatcher(const std::vector<std::string>& expressions) : expressions_(expressions) {
    for (size_t k = 0; k < expressions.size(); ++k) {
      exact_.emplace(expressions[k], static_cast<int>(k));
      by_key_[arkit_name_key(expressions[k])].push_back(static_cast<int>(k));
    }
  }

  // The expressions `name` drives (empty: none). Throws Error(where, ...) for a name whose key
  // two expressions share.
  std::vector<int> targets(const std::string& name, const std::string& where) const {
    if (const auto it = exact_.find(name); it != exact_.end()) return {it->second};
    const std::string key = arkit_name_key(name);
    if (const auto it = by_key_.find(key); it != by_key_.end()) {
      if (it->second.size() == 1) return it->second;
      std::vector<std::string> alike;
      for (int k : it->second) alike.push_back(expressions_[k]);
      throw Error(where, "\"" + name + "\" matches the face model's expressions " + comma_list(alike) +
                             " alike; name one of them exactly");
    }
    if (ends_with(key, "_l") || ends_with(key, "_r")) return {};
    const auto left = by_key_.find(key + "_l"), right = by_key_.find(key + "_r");
    if (left != by_key_.end() && right != by_key_.end() && left->second.size() == 1 && right->second.size() == 1)
      return {left->second.front(), right->second.front()};
    return {};
  }

  // Records that `name` drives `targets`; throws Error(where, ...) when another name drives one of them.
  void claim(const std::string& name, const std::vector<int>& targets, const std::string& where) {
    for (int k : targets) {
      const auto [it, inserted] = driver_.emplace(k, name);
      if (!inserted && it->second != name)
        throw Error(where, "\"" + name + "\" and \"" + it->second + "\" both drive the expression \"" +
                               expressions_[k] + "\"; keep one of them");
    }
  }

  bool driven(int k) const { return driver_.count(k) > 0; }
  bool drives_any() const { return !driver_.empty(); }

 private:
  const std::vector<std::string>& expressions_;
  std::map<std::string, int> exact_;
  std::map<std::string, std::vector<int>> by_key_;
  std::map<int, std::string> driver_;
};

// "file:line"
std::string file_line(const std::string& source, int line) { return source + ":" + std::to_string(line); }

// Throws UnreadableTake naming the line when `line` (line `number` of `source`) holds a byte
// that is not text or is longer than kMaxTakeLineBytes.
void check_line(std::string_view line, const std::string& source, int number) {
  if (line.size() > kMaxTakeLineBytes)
    throw UnreadableTake(
        file_line(source, number),
        fmt::format("a line longer than a take's lines may be ({} bytes); is this a take?", kMaxTakeLineBytes));
  const size_t bad = first_non_text_byte(line);
  if (bad != std::string_view::npos)
    throw UnreadableTake(file_line(source, number),
                         fmt::format("column {}: byte 0x{:02X} is not text; a take is a CSV or JSON lines text file "
                                     "(is this a binary file?)",
                                     bad + 1, static_cast<unsigned>(static_cast<unsigned char>(line[bad]))));
}

// The lines of `text` with their numbers, without line ends; blank lines left out.
struct TextLine {
  int number;
  std::string_view text;
};
std::vector<TextLine> non_blank_lines(std::string_view text) {
  if (text.size() >= 3 && text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);  // UTF-8 BOM
  std::vector<TextLine> lines;
  int number = 1;
  size_t start = 0;
  while (start <= text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (!trim_space(line).empty()) lines.push_back({number, line});
    ++number;
    start = end + 1;
  }
  return lines;
}

std::vector<std::string_view> split_fields(std::string_view line) {
  std::vector<std::string_view> fields;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    if (comma == std::string_view::npos) {
      fields.push_back(line.substr(start));
      return fields;
    }
    fields.push_back(line.substr(start, comma - start));
    start = comma + 1;
  }
}

// What is wrong with a weight `value` written as `text`: "" for one within kMaxArkitExcess of
// ARKit's [0, 1] (clamped later).
std::string range_problem(double value, const std::string& text) {
  if (value >= -kMaxArkitExcess && value <= 1 + kMaxArkitExcess) return "";
  return fmt::format(
      "the weight {} is far outside ARKit's range [0, 1] (up to {:g} beyond it is clamped); is this "
      "column a blendshape weight?",
      text, kMaxArkitExcess);
}

// What is wrong with a weight's text, or "" when `value` holds a usable number.
std::string weight_problem(std::string_view token, double& value) {
  if (token.empty()) return "an empty field, expected a number";
  switch (parse_real(token, value)) {
    case NumberStatus::malformed:
      return "expected a number, got " + retarget::quoted(token);
    case NumberStatus::out_of_range:
      return "the number " + retarget::quoted(token) + " is out of range";
    case NumberStatus::ok:
      break;
  }
  if (std::isnan(value)) return retarget::quoted(token) + " is not a weight (NaN); expected a finite number";
  if (!std::isfinite(value)) return retarget::quoted(token) + " is not a weight (infinite); expected a finite number";
  return range_problem(value, std::string(token));
}

// The frames as they are read: one row of weights per frame (#expressions).
struct Frames {
  std::vector<Eigen::VectorXd> rows;
  std::vector<std::string> timecodes;
  std::vector<int> lines;
  std::vector<std::string> names;  // every name the take uses for weights, first seen first
  std::set<std::string> seen;

  void add_name(const std::string& name) {
    if (seen.insert(name).second) names.push_back(name);
  }
};

// A CSV header: each column's role, name and the expressions a weight column drives.
enum class CsvRole { timecode, count, weight };
struct CsvHeader {
  int number = 0;  // its line
  int columns = 0;
  std::vector<CsvRole> roles;
  std::vector<std::string> names;
  std::vector<std::vector<int>> targets;
};

// One frame as read, before clamping: #expressions weights.
struct TakeRow {
  Eigen::VectorXd weights;
  std::string timecode;
  int line = 0;
};

CsvHeader read_csv_header_fields(const TextLine& head, const std::string& source, NameMatcher& matcher,
                                 Frames& frames) {
  std::vector<std::string_view> header = split_fields(head.text);
  if (header.size() > 1 && trim_space(header.back()).empty()) header.pop_back();  // a trailing comma
  CsvHeader h;
  h.number = head.number;
  h.columns = static_cast<int>(header.size());
  const int columns = h.columns;
  h.roles.assign(columns, CsvRole::weight);
  h.names.resize(columns);
  h.targets.resize(columns);
  std::map<std::string, int> column_of;  // lower-case name -> column (from 0)
  const std::string header_at = file_line(source, head.number);
  for (int c = 0; c < columns; ++c) {
    const std::string name(unquote(header[c]));
    h.names[c] = name;
    const std::string label = fmt::format("column {}", c + 1);
    if (name.empty()) throw Error(header_at, label + ": an empty column name");
    double number = 0;
    if (parse_real(name, number) == NumberStatus::ok)
      throw Error(header_at, label + ": expected a header of column names (Timecode, BlendShapeCount, EyeBlinkLeft, " +
                                 "...) on the first line, got the number " + retarget::quoted(name) +
                                 "; the take has no header");
    const auto [it, inserted] = column_of.emplace(lowercase(name), c);
    if (!inserted)
      throw Error(header_at, fmt::format("{} ({}): the same name as column {} ({})", label, name, it->second + 1,
                                         h.names[it->second]));
    const std::string key = lowercase(name);
    if (key == "timecode") {
      h.roles[c] = CsvRole::timecode;
    } else if (key == "blendshapecount") {
      h.roles[c] = CsvRole::count;
    } else {
      frames.add_name(name);
      h.targets[c] = matcher.targets(name, header_at + ": " + label);
      matcher.claim(name, h.targets[c], header_at + ": " + label);
    }
  }
  if (!matcher.drives_any()) {
    std::vector<std::string> names(h.names.begin(), h.names.begin() + std::min(columns, 8));
    throw Error(header_at,
                fmt::format("no column of the header names an expression of the face model ({} column{}: "
                            "{}{}); a take's first line names its blendshapes (EyeBlinkLeft, JawOpen, ...)",
                            columns, columns == 1 ? "" : "s", comma_list(names), columns > 8 ? ", ..." : ""));
  }
  return h;
}

// A CSV header (read_csv_header_fields); any problem with it is an UnreadableTake: no row can be
// read without it.
CsvHeader read_csv_header(const TextLine& head, const std::string& source, NameMatcher& matcher, Frames& frames) {
  check_line(head.text, source, head.number);
  try {
    return read_csv_header_fields(head, source, matcher, frames);
  } catch (const UnreadableTake&) {
    throw;
  } catch (const Error& e) {
    throw UnreadableTake(e.where(), e.detail());
  }
}

TakeRow read_csv_row(const CsvHeader& h, const TextLine& line, const std::string& source, int expressions) {
  const int columns = h.columns;
  const std::string where = file_line(source, line.number);
  std::vector<std::string_view> fields = split_fields(line.text);
  if (static_cast<int>(fields.size()) == columns + 1 && trim_space(fields.back()).empty()) fields.pop_back();
  const int count = static_cast<int>(fields.size());
  if (count < columns)
    throw Error(where, fmt::format("{} fields but the header (line {}) has {}: column {} ({}) is missing", count,
                                   h.number, columns, count + 1, h.names[count]));
  if (count > columns)
    throw Error(where, fmt::format("{} fields but the header (line {}) has {}: column {} has no name", count, h.number,
                                   columns, columns + 1));
  TakeRow row;
  row.weights = Eigen::VectorXd::Zero(expressions);
  row.line = line.number;
  for (int c = 0; c < columns; ++c) {
    if (h.roles[c] == CsvRole::timecode) row.timecode = std::string(unquote(fields[c]));
    if (h.roles[c] != CsvRole::weight || h.targets[c].empty()) continue;
    double value = 0;
    const std::string problem = weight_problem(trim_space(fields[c]), value);
    if (!problem.empty()) throw Error(where, fmt::format("column {} ({}): {}", c + 1, h.names[c], problem));
    for (int k : h.targets[c]) row.weights[k] = value;
  }
  return row;
}

void add_row(Frames& frames, TakeRow&& row) {
  frames.rows.push_back(std::move(row.weights));
  frames.timecodes.push_back(std::move(row.timecode));
  frames.lines.push_back(row.line);
}

void read_csv(const std::string& text, const std::string& source, NameMatcher& matcher, int expressions,
              Frames& frames) {
  const std::vector<TextLine> lines = non_blank_lines(text);
  if (lines.empty()) throw Error(source, "an empty take: no header and no frames");
  const CsvHeader header = read_csv_header(lines.front(), source, matcher, frames);
  if (lines.size() == 1) throw Error(source, fmt::format("no frames: only a header (line {})", header.number));
  for (size_t l = 1; l < lines.size(); ++l) {
    check_line(lines[l].text, source, lines[l].number);
    add_row(frames, read_csv_row(header, lines[l], source, expressions));
  }
}

// "column N" of the value of `key` in the JSON text of one line, or "" when it cannot be found
// there as written (a key with escapes).
std::string json_column(std::string_view line, const std::string& key) {
  const std::string quoted_key = "\"" + key + "\"";
  size_t pos = line.find(quoted_key);
  if (pos == std::string_view::npos) return "";
  pos += quoted_key.size();
  while (pos < line.size() && (std::isspace(static_cast<unsigned char>(line[pos])) || line[pos] == ':')) ++pos;
  return fmt::format(" (column {})", pos + 1);
}

std::string json_type(const TakeJson& value) {
  if (value.is_string()) return "the string " + retarget::quoted(value.get<std::string>());
  if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
  if (value.is_null()) return "null";
  if (value.is_array()) return "an array";
  if (value.is_object()) return "an object";
  return value.dump();
}

// The parse error's text without the library's prefix ("[json.exception.parse_error.101] parse
// error at line 1, column 5: ").
std::string json_reason(const std::string& what) {
  const size_t column = what.find("column ");
  if (column != std::string::npos) {
    const size_t colon = what.find(": ", column);
    if (colon != std::string::npos) return what.substr(colon + 2);
  }
  return what;
}

namespace arkit_detail {

// MediaPipe's FaceLandmarker blendshapes for one face, [{"index": 0, "score": 0.01, "categoryName":
// "_neutral", "displayName": ""}, ...], as an object of categoryName -> score; a list of such
// lists (one per face) gives the first face's. Throws retarget::Error(where) naming `label` and
// the entry for anything else.
TakeJson categories_as_weights(const TakeJson& list, const std::string& where, const std::string& label) {
  if (!list.is_array())
    throw Error(where, label + ": expected MediaPipe's list of {\"categoryName\": ..., \"score\": ...}, got " +
                           json_type(list));
  const TakeJson* face = &list;
  if (!list.empty() && list.front().is_array()) face = &list.front();  // one list per face: the first
  TakeJson weights = TakeJson::object();
  for (size_t k = 0; k < face->size(); ++k) {
    const TakeJson& entry = (*face)[k];
    const std::string at = fmt::format("{}, entry {}", label, k + 1);
    if (!entry.is_object())
      throw Error(where, at + ": expected {\"categoryName\": ..., \"score\": ...}, got " + json_type(entry));
    const auto name = entry.find("categoryName");
    if (name == entry.end() || !name->is_string()) throw Error(where, at + ": no \"categoryName\" string");
    const auto score = entry.find("score");
    if (score == entry.end()) throw Error(where, at + " (\"" + name->get<std::string>() + "\"): no \"score\"");
    if (weights.contains(name->get<std::string>()))
      throw Error(where, at + ": \"" + name->get<std::string>() + "\" is listed twice");
    weights[name->get<std::string>()] = *score;
  }
  return weights;
}

}  // namespace arkit_detail

// One JSON line's frame; targets_of: the expressions each name seen so far drives.
TakeRow read_jsonl_row(const TextLine& line, const std::string& source, NameMatcher& matcher, int expressions,
                       Frames& frames, std::vector<std::string>& unused_keys,
                       std::map<std::string, std::vector<int>>& targets_of) {
  const std::string where = file_line(source, line.number);
  TakeJson object;
  try {
    object = TakeJson::parse(line.text);
  } catch (const TakeJson::parse_error& e) {
    const size_t byte = e.byte;
    // Python's json.dumps writes NaN and Infinity, which JSON does not have.
    for (size_t p = byte > 10 ? byte - 10 : 0; p < byte && p < line.text.size(); ++p)
      for (const std::string_view literal : {"NaN", "Infinity"})
        if (line.text.substr(p, literal.size()) == literal)
          throw Error(where, fmt::format("column {}: {} is not a weight; expected a finite number", p + 1, literal));
    throw Error(where, fmt::format("column {}: not valid JSON: {}", byte, json_reason(e.what())));
  } catch (const TakeJson::out_of_range&) {  // a number beyond a double's range: 1e999
    throw Error(where, "a number too large for a double (beyond 1.8e308); expected weights in [0, 1]");
  } catch (const TakeJson::exception& e) {
    throw Error(where, std::string("not valid JSON: ") + json_reason(e.what()));
  }
  // MediaPipe's list form, a line of its own: [{"categoryName": name, "score": weight}, ...].
  if (object.is_array()) object = TakeJson{{"blendshapes", std::move(object)}};
  if (!object.is_object())
    throw Error(where,
                "column 1: expected one JSON object per line ({\"timecode\": ..., \"weights\": {name: "
                "weight, ...}} or {name: weight, ...}) or MediaPipe's list of {\"categoryName\": ..., \"score\": "
                "...}, got " +
                    json_type(object));
  TakeRow row;
  row.line = line.number;
  if (const auto it = object.find("timecode"); it != object.end()) {
    if (it->is_string())
      row.timecode = it->get<std::string>();
    else if (it->is_number())
      row.timecode = it->dump();
    else
      throw Error(where, "key \"timecode\"" + json_column(line.text, "timecode") +
                             ": expected a string or a number, got " + json_type(*it));
  }
  const TakeJson* weights = &object;
  TakeJson listed;  // MediaPipe's categories as name -> score
  if (const auto it = object.find("blendshapes"); it != object.end() && object.find("weights") == object.end()) {
    listed =
        arkit_detail::categories_as_weights(*it, where, "key \"blendshapes\"" + json_column(line.text, "blendshapes"));
    weights = &listed;
    for (const auto& [key, value] : object.items())
      if (key != "timecode" && key != "blendshapes" &&
          std::find(unused_keys.begin(), unused_keys.end(), key) == unused_keys.end())
        unused_keys.push_back(key);
  } else if (const auto it = object.find("weights"); it != object.end()) {
    if (!it->is_object())
      throw Error(where, "key \"weights\"" + json_column(line.text, "weights") +
                             ": expected an object of name -> weight, got " + json_type(*it));
    weights = &*it;
    for (const auto& [key, value] : object.items())
      if (key != "timecode" && key != "weights" &&
          std::find(unused_keys.begin(), unused_keys.end(), key) == unused_keys.end())
        unused_keys.push_back(key);
  }
  row.weights = Eigen::VectorXd::Zero(expressions);
  std::vector<std::string> named;  // the weights' names on this line
  for (const auto& [name, value] : weights->items()) {
    if (weights == &object && name == "timecode") continue;
    named.push_back(name);
    const std::string label = "key \"" + name + "\"" + json_column(line.text, name);
    auto it = targets_of.find(name);
    if (it == targets_of.end()) {
      it = targets_of.emplace(name, matcher.targets(name, where + ": " + label)).first;
      frames.add_name(name);
    }
    matcher.claim(name, it->second, where + ": " + label);
    if (it->second.empty()) continue;
    if (!value.is_number()) throw Error(where, label + ": expected a number, got " + json_type(value));
    const double w = value.get<double>();
    if (!std::isfinite(w)) throw Error(where, label + ": " + value.dump() + " is not a finite number");
    if (const std::string problem = range_problem(w, value.dump()); !problem.empty())
      throw Error(where, label + ": " + problem);
    for (int k : it->second) row.weights[k] = w;
  }
  if (!named.empty() && !matcher.drives_any()) {
    if (named.size() > 8) named.resize(8), named.push_back("...");
    throw UnreadableTake(where,
                         "no name on this line (nor on a line before it) names an expression of the face "
                         "model (" +
                             comma_list(named) +
                             "); a take's weights are named as ARKit names them "
                             "(eyeBlinkLeft, jawOpen, ...)");
  }
  return row;
}

void read_jsonl(const std::string& text, const std::string& source, NameMatcher& matcher, int expressions,
                Frames& frames, std::vector<std::string>& unused_keys) {
  const std::vector<TextLine> lines = non_blank_lines(text);
  if (lines.empty()) throw Error(source, "an empty take: no frames");
  std::map<std::string, std::vector<int>> targets_of;  // name -> the expressions it drives
  for (const TextLine& line : lines) {
    check_line(line.text, source, line.number);
    add_row(frames, read_jsonl_row(line, source, matcher, expressions, frames, unused_keys, targets_of));
  }
}

// Clamps `weights` into [0, 1], counting into take.clamped and take.largest_excess.
void clamp_weights(Eigen::VectorXd& weights, ArkitTake& take) {
  for (Eigen::Index k = 0; k < weights.size(); ++k) {
    double& w = weights[k];
    if (w < 0 || w > 1) {
      ++take.clamped;
      take.largest_excess = std::max(take.largest_excess, w < 0 ? -w : w - 1);
      w = std::clamp(w, 0.0, 1.0);
    }
  }
}

// take.unused and take.missing from the names read.
void name_reports(const Frames& frames, const std::vector<std::string>& unused_keys, const NameMatcher& matcher,
                  ArkitTake& take) {
  NameMatcher names_only(take.expressions);
  for (const std::string& name : frames.names)
    if (names_only.targets(name, take.source).empty()) take.unused.push_back(name);
  for (const std::string& key : unused_keys) take.unused.push_back(key);
  for (int k = 0; k < static_cast<int>(take.expressions.size()); ++k)
    if (!matcher.driven(k)) take.missing.push_back(take.expressions[k]);
}

// The reports of the take (see the header), once each.
void report_take(const ArkitTake& take) {
  std::vector<std::string> pose, other;
  for (const std::string& name : take.unused) (is_arkit_pose_column(name) ? pose : other).push_back(name);
  if (!other.empty())
    log::warn("{}: {} name{} match{} no expression of the face model, not used: {}", take.source, other.size(),
              other.size() == 1 ? "" : "s", other.size() == 1 ? "es" : "", comma_list(other));
  if (!pose.empty())
    log::info("{}: not used (head and eye rotations; retargeting carries the blendshapes): {}", take.source,
              comma_list(pose));
  if (!take.missing.empty())
    log::warn("{}: {} of the face model's {} expressions in no column of the take, held at 0: {}", take.source,
              take.missing.size(), take.expressions.size(), comma_list(take.missing));
  if (take.clamped > 0)
    log::warn("{}: {} weight{} outside ARKit's range [0, 1] clamped into it (the farthest by {:.6g})", take.source,
              take.clamped, take.clamped == 1 ? "" : "s", take.largest_excess);
}

}  // namespace arkit_take_detail

using namespace arkit_take_detail;

bool ArkitTake::has_timecodes() const {
  return std::any_of(timecodes.begin(), timecodes.end(), [](const std::string& t) { return !t.empty(); });
}

std::string arkit_name_key(const std::string& name) {
  std::string text = lowercase(trim_space(name));
  std::string side;
  const size_t n = text.size();
  if (n > 2 && is_separator(text[n - 2]) && (text[n - 1] == 'l' || text[n - 1] == 'r')) {
    side = text.substr(n - 1);
    text.resize(n - 2);
  } else if (n > 4 && ends_with(text, "left")) {
    side = "l";
    text.resize(n - 4);
  } else if (n > 5 && ends_with(text, "right")) {
    side = "r";
    text.resize(n - 5);
  }
  std::string key;
  for (char c : text)
    if (!is_separator(c)) key += c;
  return side.empty() ? key : key + "_" + side;
}

std::vector<std::vector<int>> match_arkit_names(const std::vector<std::string>& names,
                                                const std::vector<std::string>& expressions, const std::string& where) {
  NameMatcher matcher(expressions);
  std::vector<std::vector<int>> targets;
  for (const std::string& name : names) {
    targets.push_back(matcher.targets(name, where));
    matcher.claim(name, targets.back(), where);
  }
  return targets;
}

bool is_arkit_pose_column(const std::string& name) {
  static const std::set<std::string> pose = {"headyaw",      "headpitch",   "headroll",    "lefteyeyaw",
                                             "lefteyepitch", "lefteyeroll", "righteyeyaw", "righteyepitch",
                                             "righteyeroll", "_neutral"};
  return pose.count(lowercase(trim_space(name))) > 0;
}

ArkitTakeFormat arkit_take_format(const std::string& path, const std::string& text) {
  const std::string extension = lowercase(fs::path(path).extension().string());
  if (extension == ".csv") return ArkitTakeFormat::csv;
  if (extension == ".jsonl" || extension == ".ndjson" || extension == ".json") return ArkitTakeFormat::jsonl;
  const std::vector<TextLine> lines = non_blank_lines(text);
  return !lines.empty() &&
                 (trim_space(lines.front().text).front() == '{' || trim_space(lines.front().text).front() == '[')
             ? ArkitTakeFormat::jsonl
             : ArkitTakeFormat::csv;
}

ArkitTake parse_arkit_take(const std::string& text, const std::string& source, ArkitTakeFormat format,
                           const std::vector<std::string>& expressions) {
  NameMatcher matcher(expressions);  // every line is checked for bytes that are not text as it is read
  const int count = static_cast<int>(expressions.size());
  Frames frames;
  std::vector<std::string> unused_keys;
  if (format == ArkitTakeFormat::csv)
    read_csv(text, source, matcher, count, frames);
  else
    read_jsonl(text, source, matcher, count, frames, unused_keys);

  ArkitTake take;
  take.source = source;
  take.format = format;
  take.expressions = expressions;
  take.timecodes = std::move(frames.timecodes);
  take.lines = std::move(frames.lines);
  const int rows = static_cast<int>(frames.rows.size());
  take.weights.resize(rows, count);
  for (int f = 0; f < rows; ++f) {
    clamp_weights(frames.rows[f], take);
    take.weights.row(f) = frames.rows[f].transpose();
  }
  name_reports(frames, unused_keys, matcher, take);
  report_take(take);
  return take;
}

struct ArkitRowParser::State {
  State(std::string source_, ArkitTakeFormat format_, std::vector<std::string> expressions_)
      : source(std::move(source_)), format(format_), expressions(std::move(expressions_)), matcher(expressions) {}
  std::string source;
  ArkitTakeFormat format;
  std::vector<std::string> expressions;
  NameMatcher matcher;  // refers to `expressions`: State is neither copied nor moved
  Frames names;         // only the names: the rows go to the caller
  std::optional<CsvHeader> header;
  std::vector<std::string> unused_keys;
  std::map<std::string, std::vector<int>> targets_of;
  ArkitTake counts;  // clamped, largest_excess
  int frames = 0;
};

ArkitRowParser::ArkitRowParser(std::string source, ArkitTakeFormat format, std::vector<std::string> expressions)
    : state_(std::make_unique<State>(std::move(source), format, std::move(expressions))) {}

ArkitRowParser::~ArkitRowParser() = default;

bool ArkitRowParser::has_header() const { return state_->format == ArkitTakeFormat::jsonl || state_->header; }

void ArkitRowParser::header(std::string_view text, int line) {
  if (state_->format != ArkitTakeFormat::csv) throw Error(state_->source, "JSON lines have no header");
  if (state_->header) throw Error(file_line(state_->source, line), "a second header");
  State& s = *state_;
  s.header = read_csv_header({line, text}, s.source, s.matcher, s.names);
}

std::optional<ArkitRow> ArkitRowParser::row(std::string_view text, int line) {
  State& s = *state_;
  if (line == 1 && text.size() >= 3 && text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);  // UTF-8 BOM
  if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
  check_line(text, s.source, line);
  if (trim_space(text).empty()) return std::nullopt;
  if (!has_header()) {
    header(text, line);
    return std::nullopt;
  }
  const int count = static_cast<int>(s.expressions.size());
  TakeRow row = s.format == ArkitTakeFormat::csv
                    ? read_csv_row(*s.header, {line, text}, s.source, count)
                    : read_jsonl_row({line, text}, s.source, s.matcher, count, s.names, s.unused_keys, s.targets_of);
  clamp_weights(row.weights, s.counts);
  ++s.frames;
  return ArkitRow{std::move(row.weights), std::move(row.timecode), row.line};
}

int ArkitRowParser::frames() const { return state_->frames; }

ArkitTake ArkitRowParser::reports() const {
  const State& s = *state_;
  ArkitTake take;
  take.source = s.source;
  take.format = s.format;
  take.expressions = s.expressions;
  take.weights.resize(0, static_cast<Eigen::Index>(s.expressions.size()));
  take.clamped = s.counts.clamped;
  take.largest_excess = s.counts.largest_excess;
  name_reports(s.names, s.unused_keys, s.matcher, take);
  return take;
}

void report_arkit_take(const ArkitTake& take) { report_take(take); }

ArkitTake read_arkit_take(const std::string& path, const std::vector<std::string>& expressions) {
  if (fs::is_directory(path)) throw Error(path, "is a folder; expected a take file (.csv or .jsonl)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, "cannot read the take: no such file or no permission");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw Error(path, "cannot read the take: a read error");
  const std::string content = text.str();
  return parse_arkit_take(content, path, arkit_take_format(path, content), expressions);
}

std::string arkit_frames_csv(const ArkitTake& take) {
  std::string text = "frame,timecode\n";
  for (int f = 0; f < take.frames(); ++f) {
    const std::string& timecode = take.timecodes[f];
    std::string field = timecode;
    if (timecode.find_first_of(",\"\r\n") != std::string::npos) {
      field = "\"";
      for (char c : timecode) field += c == '"' ? std::string("\"\"") : std::string(1, c);
      field += "\"";
    }
    text += std::to_string(f) + "," + field + "\n";
  }
  return text;
}

}  // namespace retarget
