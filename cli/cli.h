// The `retarget` command line: one function per subcommand, so main.cpp stays a dispatcher.
#pragma once

namespace retarget::cli {

// argv[0] is the subcommand name. Return the process exit code.
int run(int argc, char** argv);

}  // namespace retarget::cli
