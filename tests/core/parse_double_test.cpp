#include "core/parse_double.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

using retarget::parse_double;

namespace {

// parse_double and std::from_chars on the same text: the same end, error and value (bit for bit,
// so -0.0 and 0.0 differ). The value is compared only where from_chars sets it.
void require_same_as_from_chars(const std::string& text) {
  INFO("text: \"" << text << "\"");
  const char* first = text.data();
  const char* last = text.data() + text.size();
  double fast = 12345.0, reference = 12345.0;
  const auto ours = parse_double(first, last, fast);
  const auto theirs = std::from_chars(first, last, reference);
  REQUIRE(ours.ec == theirs.ec);
  REQUIRE(ours.ptr - first == theirs.ptr - first);
  std::uint64_t a = 0, b = 0;
  std::memcpy(&a, &fast, sizeof a);
  std::memcpy(&b, &reference, sizeof b);
  REQUIRE(a == b);
}

std::string printed(const char* format, int precision, double value) {
  char buffer[512];
  std::snprintf(buffer, sizeof buffer, format, precision, value);
  return buffer;
}

}  // namespace

TEST_CASE("parse_double: odd and edge texts give what from_chars gives", "[parse_double]") {
  const std::vector<std::string> texts = {"0",
                                          "-0",
                                          "-0.0",
                                          "0.0",
                                          "1",
                                          "-1",
                                          "1.",
                                          "-1.",
                                          ".5",
                                          "-.5",
                                          ".",
                                          "-",
                                          "",
                                          "+1",
                                          "--1",
                                          "-+1",
                                          "1e",
                                          "1e+",
                                          "1e-",
                                          "1E5",
                                          "1e-5",
                                          "1e+05",
                                          "1e0022",
                                          "1e00022",
                                          "12e-22",
                                          "1e22",
                                          "1e23",
                                          "1e-22",
                                          "1e-23",
                                          "123456789012345",
                                          "1234567890123456",
                                          "12345678901234567890123",
                                          "0.123456789012345",
                                          "0.1234567890123456",
                                          "9007199254740993",
                                          "0.000000000000000000000123",
                                          "000000000000000000000012.5",
                                          "100000000000000000000000",
                                          "1e-400",
                                          "1e400",
                                          "-1e400",
                                          "inf",
                                          "-inf",
                                          "nan",
                                          "infinity",
                                          "1.5x",
                                          "1.2.3",
                                          "1e5e3",
                                          "0x1p3",
                                          "1.5 2",
                                          "1.5\n",
                                          "1.5#c",
                                          "7.0e",
                                          "2.5E+3 ",
                                          "-0.0123456",
                                          "3.14159265358979",
                                          "179769313486231570000000",
                                          "4.9e-324",
                                          "2.2250738585072014e-308"};
  for (const std::string& text : texts) require_same_as_from_chars(text);
}

TEST_CASE("parse_double: printed doubles of every size and format read back as from_chars reads them",
          "[parse_double]") {
  std::mt19937_64 random(2026);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> scale(-40, 40), digits(0, 17);
  for (int i = 0; i < 20000; ++i) {
    const double value = unit(random) * std::pow(10.0, scale(random));
    const int precision = digits(random);
    require_same_as_from_chars(printed("%.*f", precision % 12, value));
    require_same_as_from_chars(printed("%.*g", precision, value));
    require_same_as_from_chars(printed("%.*e", precision, value));
  }
  for (int i = 0; i < 20000; ++i) {  // any finite bit pattern, printed to round-trip
    std::uint64_t bits = random();
    double value = 0;
    std::memcpy(&value, &bits, sizeof value);
    if (!std::isfinite(value)) continue;
    require_same_as_from_chars(printed("%.*g", 17, value));
  }
}

TEST_CASE("parse_double: mesh-file decimals take the fast path", "[parse_double]") {
  for (const char* text : {"-0.0123456", "12.5e-3", "0.000000", "-123.456789", "1e-5", "41"}) {
    INFO(text);
    double value = 0;
    REQUIRE(retarget::parse_double_detail::parse_plain_decimal(text, text + std::strlen(text), value) != nullptr);
  }
  for (const char* text : {"1.", ".5", "1e400", "0.12345678901234567", "nan"}) {
    INFO(text);
    double value = 0;
    REQUIRE(retarget::parse_double_detail::parse_plain_decimal(text, text + std::strlen(text), value) == nullptr);
  }
}
