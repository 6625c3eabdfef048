// Line-by-line tokens of a text mesh file (the OFF reader and ASCII PLY bodies), with the line
// number every message names, and strict number parsing for the tokens.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace retarget {

class TextLines {
 public:
  // text: the whole file; reading starts at byte `start`, which is on line `line` (from 1).
  // comment: the character that starts a comment running to the end of its line ('\0': none).
  TextLines(std::string_view text, size_t start, int line, char comment);

  // The next line with at least one token, split at blanks (' ', '\t', '\r', '\v', '\f');
  // false at the end of the text. line() is then that line's number.
  bool next(std::vector<std::string_view>& tokens);

  int line() const { return line_; }
  size_t remaining_bytes() const { return text_.size() - pos_; }

 private:
  std::string_view text_;
  size_t pos_;
  int line_;
  int next_line_;
  char comment_;
};

// What a number token held.
enum class NumberStatus { ok, malformed, out_of_range };

// A decimal floating-point number, the whole token (an optional leading '+' allowed; "nan" and
// "inf" parse, so callers check std::isfinite for coordinates).
NumberStatus parse_real(std::string_view token, double& value);

// A decimal integer, the whole token, in [min, max].
NumberStatus parse_integer(std::string_view token, long long min, long long max, long long& value);

// The token as a message quotes it: at most 40 characters, then "...". Call it qualified
// (retarget::quoted): with <iomanip> in the same unit, argument-dependent lookup also finds
// std::quoted.
std::string quoted(std::string_view token);

// The shortest decimal text that reads back as the same double (std::to_chars).
std::string shortest_text(double value);

}  // namespace retarget
