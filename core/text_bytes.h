// Is it text? The check readers of text formats (configs, takes, tables, meshes) make before
// parsing, so that a binary file gets one clear message naming the first byte that is not text.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace retarget {

// The first byte of `text` that is not text: a control character other than tab, carriage
// return and line feed (NUL included), DEL, or a byte that is not part of valid UTF-8 (an
// overlong form, a surrogate, a code point above U+10FFFF, a sequence cut short). npos when all
// of it is text. Readers of text formats call it before parsing, so that a binary file gets one
// clear message rather than a parse error about its first bytes. any_high_bytes: bytes 0x80 and
// above all pass (formats that may hold Latin-1 comments: OBJ, OFF).
size_t first_non_text_byte(std::string_view text, bool any_high_bytes = false);

// "line L, column C: byte 0xNN is not text" for the byte at `offset` of `text` (lines and
// columns from 1, counted in bytes).
std::string non_text_message(std::string_view text, size_t offset);

// Throws retarget::Error(where, "line L, column C: byte 0xNN is not text; <kind> (is this a
// binary file?)") for the first byte of `text` that is not text; kind says what the file should
// be ("an OBJ file is text").
void require_text(std::string_view text, const std::string& where, const std::string& kind,
                  bool any_high_bytes = false);

}  // namespace retarget
