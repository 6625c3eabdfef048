// Runs a `retarget` subcommand function in-process as the dispatcher calls it (argv[0] = its
// name), with standard output captured: the CLI tests' way of running a command as a user would.
#pragma once

#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace retarget::test {

// command: e.g. cli::synth_command; args: everything after the subcommand's name. Returns the
// exit code; what the command printed goes to *printed when given. Exceptions pass through
// (standard output restored first).
inline int run_command(int (*command)(int, char**), const std::string& name, std::vector<std::string> args,
                       std::string* printed = nullptr) {
  args.insert(args.begin(), name);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  std::ostringstream capture;
  std::streambuf* old = std::cout.rdbuf(capture.rdbuf());
  int code = 0;
  try {
    code = command(static_cast<int>(argv.size()), argv.data());
  } catch (...) {
    std::cout.rdbuf(old);
    throw;
  }
  std::cout.rdbuf(old);
  if (printed) *printed = capture.str();
  return code;
}

}  // namespace retarget::test
