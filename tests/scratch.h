// Test helpers that need nothing above core/: a scratch folder, files written byte for byte
// and the message of an expected error. tests/test_support.h adds small meshes.
#pragma once

#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <system_error>
#include <vector>

#include "core/error.h"

namespace retarget::test {

// A fresh, empty scratch folder below the build tree, unique per name.
inline std::filesystem::path scratch_dir(const std::string& name) {
  std::filesystem::path dir = std::filesystem::path(RETARGET_TEST_TMP) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// scratch_dir(name + "_" + pid), removed when the process exits: CTest may run the test cases of
// one binary in parallel processes, each building its own shared inputs.
inline std::filesystem::path process_scratch_dir(const std::string& name) {
  struct Cleanup {
    std::vector<std::filesystem::path> dirs;
    ~Cleanup() {
      for (const auto& dir : dirs) {
        std::error_code ignored;
        std::filesystem::remove_all(dir, ignored);
      }
    }
  };
  static Cleanup cleanup;
  cleanup.dirs.push_back(scratch_dir(name + "_" + std::to_string(::getpid())));
  return cleanup.dirs.back();
}

// Writes `bytes` to `path` as they are (binary); returns the path, for the reader under test.
inline std::string write_file(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
  return path.string();
}

// Writes `text` to dir/name; returns the path.
inline std::string write_file(const std::filesystem::path& dir, const std::string& name, const std::string& text) {
  return write_file(dir / name, text);
}

// The message of the retarget::Error that `f` throws; "" and a failed check if it throws none.
inline std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& error) {
    return error.what();
  }
  FAIL_CHECK("expected a retarget::Error");
  return "";
}

}  // namespace retarget::test
