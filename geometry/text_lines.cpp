#include "geometry/text_lines.h"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <system_error>

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
  const auto [end, ec] = std::from_chars(first, last, value);
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

size_t first_non_text_byte(std::string_view text) {
  const auto* bytes = reinterpret_cast<const unsigned char*>(text.data());
  const size_t n = text.size();
  for (size_t i = 0; i < n;) {
    const unsigned char c = bytes[i];
    if (c < 0x80) {
      if ((c < 0x20 && c != '\t' && c != '\n' && c != '\r') || c == 0x7F) return i;
      ++i;
      continue;
    }
    // UTF-8: the lead byte gives the length and the smallest code point (no overlong forms).
    int length = 0;
    uint32_t code = 0, smallest = 0;
    if (c >= 0xC2 && c <= 0xDF) {
      length = 2, code = c & 0x1F, smallest = 0x80;
    } else if (c >= 0xE0 && c <= 0xEF) {
      length = 3, code = c & 0x0F, smallest = 0x800;
    } else if (c >= 0xF0 && c <= 0xF4) {
      length = 4, code = c & 0x07, smallest = 0x10000;
    } else {
      return i;
    }
    if (i + static_cast<size_t>(length) > n) return i;
    for (int k = 1; k < length; ++k) {
      const unsigned char next = bytes[i + static_cast<size_t>(k)];
      if ((next & 0xC0) != 0x80) return i;
      code = (code << 6) | (next & 0x3F);
    }
    if (code < smallest || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF)) return i;
    i += static_cast<size_t>(length);
  }
  return std::string_view::npos;
}

std::string non_text_message(std::string_view text, size_t offset) {
  const std::string_view before = text.substr(0, offset);
  const size_t line_start = before.rfind('\n');
  const size_t line = 1 + static_cast<size_t>(std::count(before.begin(), before.end(), '\n'));
  const size_t column = offset - (line_start == std::string_view::npos ? 0 : line_start + 1) + 1;
  char hex[8];
  std::snprintf(hex, sizeof(hex), "0x%02X", static_cast<unsigned>(static_cast<unsigned char>(text[offset])));
  return "line " + std::to_string(line) + ", column " + std::to_string(column) + ": byte " + hex + " is not text";
}

std::string quoted(std::string_view token) {
  return "\"" + (token.size() <= 40 ? std::string(token) : std::string(token.substr(0, 40)) + "...") + "\"";
}

}  // namespace retarget
