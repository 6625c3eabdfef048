// How many threads a run may use: the CPUs this process may run on, and the bounds a requested
// thread count is checked against (options `--threads`, config keys `training.threads`).
#pragma once

#include <string>

namespace retarget {

// Every CPU this process may run on (its affinity mask: taskset, cpusets), at least 1.
// std::thread::hardware_concurrency() when the mask cannot be read. LibTorch's own default can be
// lower (1 on VMs whose vCPUs look like threads of one core).
int available_cpus();

// More threads than this many per available CPU only wait on each other (and thousands of them
// make a run crawl for minutes instead of failing).
inline constexpr int kMaxThreadsPerCpu = 4;

// What 0 threads means: OMP_NUM_THREADS when it is set to a positive number (the first of a
// list; at most kMaxThreadsPerCpu per CPU), as torchrun and job schedulers set it for the
// processes that share a machine; otherwise every available CPU.
int default_thread_count();

// The thread count to use for `requested`: 0 means default_thread_count(); 1..kMaxThreadsPerCpu x
// available_cpus() is taken as is. Throws retarget::Error(where, ...) for a negative count or one
// above that bound, saying the bound and the CPU count.
int checked_thread_count(int requested, const std::string& where);

}  // namespace retarget
