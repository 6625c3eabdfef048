// environment_with: a child's environment is this one's with some variables set.
#include "core/process_environment.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdlib>

namespace retarget {
namespace process_environment_test {

TEST_CASE("environment_with adds variables, replaces same-named ones once and keeps the rest", "[core]") {
  ::setenv("RETARGET_ENV_TEST_KEEP", "kept", 1);
  ::setenv("RETARGET_ENV_TEST_SET", "old", 1);
  const std::vector<std::string> e =
      environment_with({{"RETARGET_ENV_TEST_SET", "new"}, {"RETARGET_ENV_TEST_ADD", "a=b"}});
  const auto count = [&](const std::string& entry) { return std::count(e.begin(), e.end(), entry); };
  CHECK(count("RETARGET_ENV_TEST_KEEP=kept") == 1);
  CHECK(count("RETARGET_ENV_TEST_SET=new") == 1);
  CHECK(count("RETARGET_ENV_TEST_SET=old") == 0);
  CHECK(count("RETARGET_ENV_TEST_ADD=a=b") == 1);  // values may hold '='
  CHECK(environment_with({}).size() + 1 == e.size());
  ::unsetenv("RETARGET_ENV_TEST_KEEP");
  ::unsetenv("RETARGET_ENV_TEST_SET");
}

}  // namespace process_environment_test
}  // namespace retarget
