#include "core/cpu_threads.h"

#include <fmt/format.h>

#include <algorithm>
#include <thread>
#ifdef __linux__
#include <sched.h>
#endif

#include "core/error.h"

namespace retarget {

int available_cpus() {
#ifdef __linux__
  cpu_set_t cpus;
  if (sched_getaffinity(0, sizeof cpus, &cpus) == 0) return std::max(1, CPU_COUNT(&cpus));
#endif
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

int checked_thread_count(int requested, const std::string& where) {
  const int cpus = available_cpus();
  if (requested < 0)
    throw Error(where, fmt::format("expected a thread count >= 0 (0: all {} CPUs), got {}", cpus, requested));
  if (requested == 0) return cpus;
  const int limit = kMaxThreadsPerCpu * cpus;
  if (requested > limit)
    throw Error(where, fmt::format("{} threads is more than {} ({} per CPU; this process may use {} CPUs); "
                                   "0 uses every CPU",
                                   requested, limit, kMaxThreadsPerCpu, cpus));
  return requested;
}

}  // namespace retarget
