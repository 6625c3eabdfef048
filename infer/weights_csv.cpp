#include "infer/weights_csv.h"

#include <fmt/format.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

#include "core/error.h"
#include "core/text_bytes.h"

namespace retarget {

// Named, not anonymous: a unity build (RETARGET_UNITY) shares one anonymous namespace per batch.
namespace weights_csv_detail {

struct Record {
  int line = 0;  // where the record starts, counting from 1
  std::vector<std::string> fields;
};

// RFC 4180 records of `text`; blank lines are skipped.
std::vector<Record> parse_csv(const std::string& text, const std::string& path) {
  std::vector<Record> records;
  Record record;
  std::string field;
  bool quoted = false, was_quoted = false, any = false;
  int line = 1;
  auto end_field = [&] {
    if (!was_quoted) {  // blanks around an unquoted field are a hand edit's, not data
      const size_t first = field.find_first_not_of(" \t");
      field =
          first == std::string::npos ? std::string() : field.substr(first, field.find_last_not_of(" \t") - first + 1);
    }
    record.fields.push_back(std::move(field));
    field.clear();
    was_quoted = false;
  };
  auto end_record = [&] {
    end_field();
    if (any) records.push_back(std::move(record));
    record = Record();
    any = false;
  };
  int quote_line = 0;
  for (size_t k = 0; k < text.size(); ++k) {
    const char c = text[k];
    if (!any && record.fields.empty() && field.empty() && !was_quoted) record.line = line;
    if (quoted) {
      if (c == '"' && k + 1 < text.size() && text[k + 1] == '"') {
        field += '"';
        ++k;
      } else if (c == '"') {
        quoted = false;
      } else {
        if (c == '\n') ++line;
        field += c;
      }
      continue;
    }
    if (c == '"' && field.find_first_not_of(" \t") == std::string::npos) {
      quoted = was_quoted = any = true;
      field.clear();
      quote_line = line;
    } else if (c == ',') {
      any = true;
      end_field();
    } else if (c == '\n' || c == '\r') {
      if (c == '\r' && k + 1 < text.size() && text[k + 1] == '\n') ++k;
      end_record();
      ++line;
    } else {
      if (was_quoted && (c == ' ' || c == '\t')) continue;
      if (was_quoted)
        throw Error(fmt::format("{}:{}", path, line), "text after a closing quote; a quote inside a field is \"\"");
      if (c != ' ' && c != '\t') any = true;
      field += c;
    }
  }
  if (quoted) throw Error(fmt::format("{}:{}", path, quote_line), "a quoted field is never closed");
  end_record();
  return records;
}

double weight(const std::string& field, const std::string& where, const std::string& column) {
  const char* begin = field.c_str();
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(begin, &end);
  if (field.empty() || end != begin + field.size() || errno == ERANGE || !std::isfinite(value))
    throw Error(where, fmt::format("column \"{}\": expected a finite number, got \"{}\"", column, field));
  if (std::abs(value) > kMaxControllerWeight)
    throw Error(where, fmt::format("column \"{}\": the weight {} is out of range: a controller weight is within "
                                   "+-{:g} (rigs' ranges are about [0, 1])",
                                   column, field, kMaxControllerWeight));
  return value;
}

}  // namespace weights_csv_detail

WeightsCsv read_weights_csv(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, "cannot open the weights file");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw Error(path, "cannot read the weights file");
  return parse_weights_csv(buffer.str(), path);
}

WeightsCsv parse_weights_csv(std::string text, const std::string& path) {
  using namespace weights_csv_detail;
  if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) text.erase(0, 3);  // a UTF-8 byte order mark
  require_text(text, path, "a weights file is CSV text");
  const std::vector<Record> records = parse_csv(text, path);
  if (records.empty()) throw Error(path, "empty: expected a header frame,<controller names...>,residual_mm");

  WeightsCsv csv;
  csv.source = path;
  const Record& header = records[0];
  const std::string header_at = fmt::format("{}:{}", path, header.line);
  if (header.fields[0] != "frame")
    throw Error(header_at, fmt::format("the header should start with \"frame\", got \"{}\" (expected "
                                       "frame,<controller names...>,residual_mm)",
                                       header.fields[0]));
  const bool residual = header.fields.size() > 1 && header.fields.back() == "residual_mm";
  const size_t columns = header.fields.size();
  std::set<std::string> seen;
  for (size_t k = 1; k < columns - (residual ? 1 : 0); ++k) {
    const std::string& name = header.fields[k];
    if (name.empty()) throw Error(header_at, fmt::format("column {} has no name", k + 1));
    if (!seen.insert(name).second) throw Error(header_at, fmt::format("column \"{}\" appears twice", name));
    csv.controllers.push_back(name);
  }
  if (csv.controllers.empty()) throw Error(header_at, "the header names no controller column");

  for (size_t r = 1; r < records.size(); ++r) {
    const Record& row = records[r];
    const std::string where = fmt::format("{}:{}", path, row.line);
    if (row.fields.size() != columns)
      throw Error(where, fmt::format("{} fields, but the header has {} columns", row.fields.size(), columns));
    csv.frames.push_back(row.fields[0]);
    Eigen::VectorXd w(static_cast<Eigen::Index>(csv.controllers.size()));
    for (size_t k = 0; k < csv.controllers.size(); ++k)
      w(static_cast<Eigen::Index>(k)) = weight(row.fields[k + 1], where, csv.controllers[k]);
    csv.weights.push_back(std::move(w));
    if (residual) {
      // Informational, and `nan` when the fit had no moving vertices: any number is kept.
      const std::string& field = row.fields.back();
      char* end = nullptr;
      const double value = std::strtod(field.c_str(), &end);
      if (field.empty() || end != field.c_str() + field.size())
        throw Error(where, fmt::format("column \"residual_mm\": expected a number, got \"{}\"", field));
      csv.residual_mm.push_back(value);
    }
  }
  if (csv.weights.empty()) throw Error(path, "no rows of weights after the header");
  return csv;
}

void require_weights_controllers(const WeightsCsv& csv, const std::vector<std::string>& controllers) {
  const size_t common = std::min(csv.controllers.size(), controllers.size());
  for (size_t k = 0; k < common; ++k)
    if (csv.controllers[k] != controllers[k])
      throw Error(csv.source, fmt::format("column {} is \"{}\" but the rig's controller {} is \"{}\"; the columns must "
                                          "be the rig's controllers in its order",
                                          k + 2, csv.controllers[k], k + 1, controllers[k]));
  if (csv.controllers.size() != controllers.size()) {
    const bool more = csv.controllers.size() > controllers.size();
    throw Error(csv.source, fmt::format("{} controller columns but the rig has {} controllers; {} \"{}\"",
                                        csv.controllers.size(), controllers.size(),
                                        more ? "the file has an extra column" : "the file lacks the rig's controller",
                                        more ? csv.controllers[common] : controllers[common]));
  }
}

}  // namespace retarget
