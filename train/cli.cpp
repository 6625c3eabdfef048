#include "train/cli.h"

namespace retarget::cli {

int run(int argc, char** argv) { return 0; }

}  // namespace retarget::cli
