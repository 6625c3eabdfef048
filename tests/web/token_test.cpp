#include "web/token.h"

#include <catch2/catch.hpp>
#include <cctype>
#include <string>

using namespace retarget;

TEST_CASE("random_token: hex of the bytes asked for, different each time", "[web]") {
  const std::string a = random_token(), b = random_token();
  CHECK(a.size() == 32);
  CHECK(a != b);
  for (char c : a) CHECK((std::isdigit(static_cast<unsigned char>(c)) || (c >= 'a' && c <= 'f')));
  CHECK(random_token(4).size() == 8);
}
