// What every fuzzer shares: a retarget::Error is the expected answer to a hostile input; any
// other exception escapes and libFuzzer reports it as a crash (std::bad_alloc included).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace retarget::fuzz {

inline std::string_view bytes(const uint8_t* data, size_t size) {
  return std::string_view(reinterpret_cast<const char*>(data), size);
}

}  // namespace retarget::fuzz
