#include "core/text_bytes.h"

#include <catch2/catch.hpp>
#include <string>

namespace retarget {
namespace {

// A mesh-like text long enough to cross many 32-byte chunks.
std::string plain_text() {
  std::string text;
  for (int i = 0; i < 40; ++i) text += "v 0.125 -1.5 2e-3\r\n\tf 1 2 3\n";
  return text;
}

TEST_CASE("first_non_text_byte finds the first bad byte wherever it falls in the file", "[text_bytes]") {
  const std::string text = plain_text();
  CHECK(first_non_text_byte(text) == std::string::npos);
  CHECK(first_non_text_byte(text.substr(0, 31)) == std::string::npos);
  for (size_t at = 0; at < 100; ++at)  // every offset of the first chunks, and their edges
    for (const char bad : {'\0', '\x01', '\x1b', '\x7f', '\v'}) {
      std::string broken = text;
      broken[at] = bad;
      broken[at + 70] = '\0';  // a later bad byte does not hide the first
      CHECK(first_non_text_byte(broken) == at);
      // Vertical tabs and form feeds pass only where any high byte does.
      CHECK(first_non_text_byte(broken, true) == (bad == '\v' ? at + 70 : at));
    }
}

TEST_CASE("first_non_text_byte reads UTF-8 after and between runs of ASCII", "[text_bytes]") {
  const std::string text = plain_text();
  const std::string good = text + "# caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80\n" + text;
  CHECK(first_non_text_byte(good) == std::string::npos);
  std::string overlong = text + "\xc0\xaf" + text;
  CHECK(first_non_text_byte(overlong) == text.size());
  std::string cut = text + "\xe2\x82";  // a sequence cut short by the end
  CHECK(first_non_text_byte(cut) == text.size());
  std::string lone = good;
  lone[text.size() + 6] = '\x80';  // the continuation byte of the é, now after a plain byte
  lone[text.size() + 5] = 'e';
  CHECK(first_non_text_byte(lone) == text.size() + 6);
  CHECK(first_non_text_byte(lone, true) == std::string::npos);  // Latin-1 comments in OBJ
}

}  // namespace
}  // namespace retarget
