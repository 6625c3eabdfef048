// Where the benchmarks look for the shared real data (ICT face, Weboji rabbit): the folder
// $RETARGET_SHARED_DATA, else ../shared/data beside the source tree. Benchmarks fall back to
// built-in meshes when it is absent; nothing here is needed by the tests.
#pragma once

#include <cstdlib>
#include <filesystem>

namespace retarget::bench {

inline std::filesystem::path shared_data() {
  if (const char* env = std::getenv("RETARGET_SHARED_DATA")) return env;
  return std::filesystem::path(RETARGET_SOURCE_DIR) / ".." / "shared" / "data";
}

}  // namespace retarget::bench
