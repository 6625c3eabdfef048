// The one way every `retarget` command reads its command line: -h/--help added to its options,
// the help printed for it, the arguments parsed otherwise.
#pragma once

#include <cxxopts.hpp>
#include <optional>
#include <string>
#include <vector>

namespace retarget::cli {

// Adds "-h, --help" (last in the default group, unless the command placed it earlier) to `options`
// and parses argv (argv[0]: the
// command's name). With --help: prints the help of `groups` (empty: every group) to stdout and
// returns std::nullopt, and the command exits with 0. A malformed command line throws
// cxxopts::exceptions::exception, as options.parse does.
std::optional<cxxopts::ParseResult> parse_options(cxxopts::Options& options, int argc, char** argv,
                                                  const std::vector<std::string>& groups = {});

// Takes every `--set VALUE` and `--set=VALUE` out of argv (in order; argc shrinks) and returns
// the values. cxxopts would split a vector option's values at commas, and an override's YAML
// value may hold commas ("--set model.channels=[9, 32, 1]"). Throws retarget::Error naming
// `command` for a --set without a value.
std::vector<std::string> take_overrides(const std::string& command, int& argc, char** argv);

}  // namespace retarget::cli
