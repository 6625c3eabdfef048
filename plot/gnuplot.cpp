#include "plot/gnuplot.h"

#include <fmt/format.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/error.h"

namespace fs = std::filesystem;

namespace retarget {

namespace {

bool gnuplot_installed() {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/bin:/bin";
  size_t start = 0;
  while (start <= dirs.size()) {
    const size_t end = dirs.find(':', start);
    const std::string dir = dirs.substr(start, end == std::string::npos ? std::string::npos : end - start);
    if (!dir.empty() && fs::exists(fs::path(dir) / "gnuplot")) return true;
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return false;
}

// For the shell that popen starts: single quotes, a quote inside closed, escaped and reopened.
std::string shell_quote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

}  // namespace

std::string gnuplot_quote(const std::string& text) {
  std::string quoted = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') quoted += '\\';
    if (c == '\n') {
      quoted += "\\n";
      continue;
    }
    quoted += c;
  }
  return quoted + "\"";
}

void run_gnuplot(const std::string& script, const std::string& script_path) {
  if (!gnuplot_installed()) throw Error("plot", "gnuplot not found; scripts/setup.sh installs gnuplot-nox");
  write_file_atomically(script_path, [&](std::ostream& out) { out << script; });
  // 2>&1: gnuplot reports errors on stderr; they come back in the message.
  const std::string command = fmt::format("gnuplot {} 2>&1", shell_quote(script_path));
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) throw Error("plot", "cannot start gnuplot");
  std::string output;
  std::array<char, 4096> buffer{};
  while (size_t n = std::fread(buffer.data(), 1, buffer.size(), pipe)) output.append(buffer.data(), n);
  const int status = ::pclose(pipe);
  if (status != 0) throw Error(script_path, "gnuplot failed: " + output);
}

}  // namespace retarget
