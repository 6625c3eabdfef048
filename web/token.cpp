#include "web/token.h"

#include <fmt/format.h>

#include <random>

namespace retarget {

std::string random_token(int bytes) {
  std::random_device device;
  std::string out;
  out.reserve(2 * static_cast<size_t>(bytes));
  for (int i = 0; i < bytes; ++i) out += fmt::format("{:02x}", device() & 0xffu);
  return out;
}

}  // namespace retarget
