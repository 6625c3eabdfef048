#include "cli/command_options.h"

#include <iostream>
#include <stdexcept>

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

}  // namespace retarget::cli
