#include "cli/command_options.h"

#include <iostream>
#include <stdexcept>

#include "core/error.h"

namespace retarget::cli {

namespace {

// Whether the command placed -h itself (to keep it where its help has always listed it).
bool has_help(const cxxopts::Options& options) {
  try {
    for (const cxxopts::HelpOptionDetails& o : options.group_help("").options)
      if (o.s == "h") return true;
  } catch (const std::out_of_range&) {  // no default group yet
  }
  return false;
}

}  // namespace

std::optional<cxxopts::ParseResult> parse_options(cxxopts::Options& options, int argc, char** argv,
                                                  const std::vector<std::string>& groups) {
  if (!has_help(options)) options.add_options()("h,help", "show this help");
  cxxopts::ParseResult result = options.parse(argc, argv);
  if (result.count("help")) {
    std::cout << (groups.empty() ? options.help() : options.help(groups)) << "\n";
    return std::nullopt;
  }
  return result;
}

std::vector<std::string> take_overrides(const std::string& command, int& argc, char** argv) {
  std::vector<std::string> values;
  int kept = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--set") {
      if (i + 1 >= argc) throw Error(command, "--set needs a value: --set key.path=value");
      values.emplace_back(argv[++i]);
    } else if (arg.rfind("--set=", 0) == 0) {
      values.push_back(arg.substr(6));
    } else {
      argv[kept++] = argv[i];
    }
  }
  argc = kept;
  return values;
}

}  // namespace retarget::cli
