#include "core/text_bytes.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>

#include "core/error.h"

namespace retarget {

namespace {

// The first i' >= i where bytes[i', i' + 32) holds anything but printable ASCII, tab, line feed
// or carriage return (or where fewer than 32 bytes are left): mesh files are almost all such
// bytes, and a whole chunk is judged in a few vector instructions (checking a frame byte by byte
// cost as much as parsing it).
size_t skip_plain_ascii(const unsigned char* bytes, size_t i, size_t n) {
  constexpr size_t chunk = 32;
  for (; i + chunk <= n; i += chunk) {
    unsigned char other = 0;  // bitwise, without branches, so that the compiler vectorises it
    for (size_t k = 0; k < chunk; ++k) {
      const unsigned char c = bytes[i + k];
      other |= static_cast<unsigned char>((c < 0x20) & (c != '\t') & (c != '\n') & (c != '\r')) |
               static_cast<unsigned char>(c >= 0x7F);
    }
    if (other) break;
  }
  return i;
}

}  // namespace

size_t first_non_text_byte(std::string_view text, bool any_high_bytes) {
  const auto* bytes = reinterpret_cast<const unsigned char*>(text.data());
  const size_t n = text.size();
  for (size_t i = 0; i < n;) {
    i = skip_plain_ascii(bytes, i, n);
    if (i >= n) break;
    const unsigned char c = bytes[i];
    if (c < 0x80 || any_high_bytes) {
      const bool blank = c == '\t' || c == '\n' || c == '\r' || (any_high_bytes && (c == '\v' || c == '\f'));
      if ((c < 0x20 && !blank) || c == 0x7F) return i;
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

void require_text(std::string_view text, const std::string& where, const std::string& kind, bool any_high_bytes) {
  const size_t bad = first_non_text_byte(text, any_high_bytes);
  if (bad != std::string_view::npos)
    throw Error(where, non_text_message(text, bad) + "; " + kind + " (is this a binary file?)");
}

}  // namespace retarget
