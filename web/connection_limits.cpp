#include "web/connection_limits.h"

#include <fmt/format.h>

#include <cmath>

#include "core/error.h"

namespace retarget {

namespace {

void require_seconds(double value, const std::string& key) {
  if (!(value >= 0.1 && value <= 600) || !std::isfinite(value))
    throw Error(key, fmt::format("must be in 0.1..600 seconds, got {}", value));
}

template <typename T>
void require_range(T value, T low, T high, const std::string& key) {
  if (value < low || value > high) throw Error(key, fmt::format("must be in {}..{}, got {}", low, high, value));
}

}  // namespace

void ConnectionLimits::validate(const std::string& key_path) const {
  require_seconds(request_seconds, key_path + ".request_seconds");
  require_seconds(idle_seconds, key_path + ".idle_seconds");
  require_seconds(write_seconds, key_path + ".write_seconds");
  require_range(requests_per_connection, 1, 100000, key_path + ".requests_per_connection");
  require_range(per_client, 0, 4096, key_path + ".per_client");
  require_range(max_header_bytes, size_t{1024}, size_t{1} << 20, key_path + ".max_header_bytes");
  require_range(max_header_fields, 1, 10000, key_path + ".max_header_fields");
}

}  // namespace retarget
