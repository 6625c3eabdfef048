// Python's torch for the interop tests: exported TorchScript files must load in Python, the way
// users will read them. scripts/setup.sh installs python3-torch, so a machine without it is a
// broken set-up: the test fails and says how to fix it instead of passing without checking.
#pragma once

#include <catch2/catch.hpp>
#include <cstdio>
#include <string>

namespace retarget::test {

// The interpreter the interop tests run.
inline const std::string kPython = "/usr/bin/python3";

// Returns kPython once it has imported torch. Otherwise FAILs the current test case with
// Python's own error output and the fix.
inline std::string python_with_torch() {
  const std::string probe = kPython + " -c 'import torch' 2>&1";
  std::string output;
  int status = -1;
  if (FILE* pipe = popen(probe.c_str(), "r")) {
    char buffer[512];
    while (fgets(buffer, sizeof buffer, pipe)) output += buffer;
    status = pclose(pipe);
  }
  if (status != 0) {
    FAIL(kPython << " cannot import torch, which this test needs to load the exported files in Python. Install "
                    "python3-torch (scripts/setup.sh does). "
                 << (output.empty() ? std::string("Python printed nothing.") : "Python said:\n" + output));
  }
  return kPython;
}

}  // namespace retarget::test
