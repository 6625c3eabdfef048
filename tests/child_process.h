// `retarget` as a child process, for the tests that kill a run as a user's machine would
// (SIGKILL) and run it again: its output to a log file, its pid to kill and wait for.
// Needs RETARGET_EXE (the executable's path), defined for the test targets that use it.
#pragma once

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "core/process_environment.h"

namespace retarget::test {

// The file's bytes ("" when it does not exist).
inline std::string file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

// Starts `retarget ARGS...` with its output in `log`, `env` ("NAME=value") added to (or replacing
// in) this process's environment; returns its pid. Everything the child needs is prepared before
// the fork: between fork and exec it only calls async-signal-safe functions (this process has
// LibTorch's threads, whose locks a forked child must not wait on).
inline pid_t spawn_retarget(const std::vector<std::string>& args, const std::vector<std::string>& env,
                            const std::filesystem::path& log) {
  std::vector<std::string> all = {RETARGET_EXE};
  all.insert(all.end(), args.begin(), args.end());
  std::map<std::string, std::string> set;
  for (const std::string& entry : env) set[entry.substr(0, entry.find('='))] = entry.substr(entry.find('=') + 1);
  std::vector<std::string> environment = environment_with(set);
  std::vector<char*> argv, envp;
  for (std::string& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  for (std::string& e : environment) envp.push_back(e.data());
  envp.push_back(nullptr);
  const int out = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  REQUIRE(out >= 0);
  const pid_t child = ::fork();
  if (child == 0) {
    if (::dup2(out, STDOUT_FILENO) < 0 || ::dup2(out, STDERR_FILENO) < 0) ::_exit(126);
    ::execve(argv[0], argv.data(), envp.data());
    ::_exit(127);
  }
  ::close(out);
  return child;
}

// The same in this process's environment as it is.
inline pid_t spawn_retarget(const std::vector<std::string>& args, const std::filesystem::path& log) {
  return spawn_retarget(args, {}, log);
}

// Waits for the child; its wait status (WIFEXITED, WEXITSTATUS...).
inline int wait_for(pid_t child) {
  int status = 0;
  ::waitpid(child, &status, 0);
  return status;
}

}  // namespace retarget::test
