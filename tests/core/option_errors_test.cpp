#include "core/option_errors.h"

#include <catch2/catch.hpp>
#include <string>
#include <vector>

namespace {

std::string explain(const std::string& message, std::vector<std::string> args) {
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  return retarget::explain_option_error(message, static_cast<int>(argv.size()), argv.data());
}

}  // namespace

TEST_CASE("a value that does not parse is named with its option", "[option_errors]") {
  CHECK(explain("Argument 'abc' failed to parse", {"retarget-infer", "--bundle", "b", "--threads", "abc"}) ==
        "--threads: expected a number, got 'abc'");
  CHECK(explain("Argument \xE2\x80\x98"
                "1e11\xE2\x80\x99 failed to parse",
                {"x", "--batch=1e11"}) == "--batch: expected a whole number in the option's range, got '1e11'");
  CHECK(explain("Argument 'nan' failed to parse", {"x", "-f", "nan"}) == "-f: expected a number, got 'nan'");
  // Other messages, and values found nowhere, are left as they are.
  CHECK(explain("Option 'x' does not exist", {"x", "--x", "1"}) == "Option 'x' does not exist");
  CHECK(explain("Argument 'zz' failed to parse", {"x", "--a", "b"}) == "Argument 'zz' failed to parse");
}
