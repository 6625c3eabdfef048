// Command-line values that do not parse, said with the option's name. cxxopts reports
// "Argument 'abc' failed to parse" without saying which option the value was given to; the
// executables pass its message here with their argv.
#pragma once

#include <string>

namespace retarget {

// For cxxopts' "Argument 'V' failed to parse": "--threads: expected a whole number, got 'abc'"
// (the option found in argv as `--name V`, `--name=V` or `-n V`; "a whole number" when V reads
// as a number, which only an integer option refuses, "a number" otherwise). Any other message,
// or a value found nowhere in argv, comes back as it is.
std::string explain_option_error(const std::string& message, int argc, char** argv);

}  // namespace retarget
