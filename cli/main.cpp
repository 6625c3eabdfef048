// retarget: the training-side command line. Each subcommand lives in cli/cli.cpp.
#include <malloc.h>

#include "cli/cli.h"
#include "core/passive_wait.h"

int main(int argc, char** argv) {
  retarget::restart_with_passive_wait(argv);  // core/passive_wait.h: share cores gracefully
  // Training allocates the same large tensors every step. glibc serves blocks above 32 MB with
  // fresh mmap()s and returns them on free, so every step paid for page faults (measured: 41% of
  // the CPU time of a human VAE step). Keeping freed memory in the process halves a step
  // (bench/train_bench.cpp: human VAE batch 30, 5.85 s -> 3.1 s); the cost is that peak memory
  // is not handed back to the system until exit.
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  return retarget::cli::run(argc, argv);
}
