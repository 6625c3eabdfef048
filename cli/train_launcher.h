// `retarget train CONFIG --nproc N`: N local data-parallel workers (train/data_parallel.h), as
// torchrun's standalone mode starts them. The launcher picks a free loopback port, starts this
// executable N times with the same arguments (without --nproc) and torchrun's variables
// (WORLD_SIZE, RANK, LOCAL_RANK, LOCAL_WORLD_SIZE, MASTER_ADDR=127.0.0.1, MASTER_PORT, and
// OMP_NUM_THREADS = the CPUs / N unless it is set, so that the workers share the cores), and
// waits. When a worker fails (a non-zero exit or a signal), the others are stopped (SIGTERM, then
// SIGKILL after 10 s) and the launcher fails naming the rank; rank 0's checkpoints stay, so
// `--resume` (with any --nproc) continues from the last one. A launcher that is killed takes its
// workers with it (PR_SET_PDEATHSIG).
#pragma once

#include <string>
#include <vector>

namespace retarget::cli {

// args: the command line after the executable's name ("train", CONFIG, ...), without --nproc.
// Returns 0 when every worker succeeded; throws retarget::Error otherwise.
int launch_local_workers(int nproc, const std::vector<std::string>& args);

}  // namespace retarget::cli
