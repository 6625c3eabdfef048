#include "geometry/text_lines.h"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <system_error>

#include "core/parse_double.h"

namespace retarget {

namespace {
bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }
}  // namespace

TextLines::TextLines(std::string_view text, size_t start, int line, char comment)
    : text_(text), pos_(std::min(start, text.size())), line_(line), next_line_(line), comment_(comment) {}

bool TextLines::next(std::vector<std::string_view>& tokens) {
  tokens.clear();
  while (pos_ < text_.size()) {
    const char* begin = text_.data() + pos_;
    const void* newline = std::memchr(begin, '\n', text_.size() - pos_);
    const size_t length = newline ? static_cast<const char*>(newline) - begin : text_.size() - pos_;
    std::string_view line(begin, length);
    pos_ += length + (newline ? 1 : 0);
    line_ = next_line_++;
    if (comment_ != '\0') line = line.substr(0, line.find(comment_));
    for (size_t i = 0; i < line.size();) {
      while (i < line.size() && is_blank(line[i])) ++i;
      const size_t first = i;
      while (i < line.size() && !is_blank(line[i])) ++i;
      if (i > first) tokens.push_back(line.substr(first, i - first));
    }
    if (!tokens.empty()) return true;
  }
  return false;
}

NumberStatus parse_real(std::string_view token, double& value) {
  const char* first = token.data();
  const char* last = token.data() + token.size();
  if (first != last && *first == '+') ++first;  // from_chars refuses a leading '+'
  if (first != last && (*first == '+' || (first != token.data() && *first == '-'))) return NumberStatus::malformed;
  const auto [end, ec] = parse_double(first, last, value);
  if (ec == std::errc::result_out_of_range) return NumberStatus::out_of_range;
  if (ec != std::errc() || end != last) return NumberStatus::malformed;
  return NumberStatus::ok;
}

NumberStatus parse_integer(std::string_view token, long long min, long long max, long long& value) {
  const char* first = token.data();
  const char* last = token.data() + token.size();
  if (first != last && *first == '+') ++first;
  if (first != last && (*first == '+' || (first != token.data() && *first == '-'))) return NumberStatus::malformed;
  const auto [end, ec] = std::from_chars(first, last, value);
  if (ec == std::errc::result_out_of_range) return NumberStatus::out_of_range;
  if (ec != std::errc() || end != last) return NumberStatus::malformed;
  return value < min || value > max ? NumberStatus::out_of_range : NumberStatus::ok;
}

std::string shortest_text(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

std::string quoted(std::string_view token) {
  return "\"" + (token.size() <= 40 ? std::string(token) : std::string(token.substr(0, 40)) + "...") + "\"";
}

}  // namespace retarget
