// `retarget-infer`'s whole command line as a function, so that the executable (infer/main.cpp)
// and `retarget pipeline` (its inference stages) run the same code.
#pragma once

namespace retarget {

// argv[0] is the program's name; the options are retarget-infer's (--help lists them). Returns
// the exit status: 0 all done, 1 some inputs failed (reported, the others written), 2 nothing
// ran (bad options or bundle, the message on standard error), 3 an unexpected error.
int infer_command(int argc, char** argv);

}  // namespace retarget
