#include "core/cpu_threads.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
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

int default_thread_count() {
  const int cpus = available_cpus();
  const char* text = std::getenv("OMP_NUM_THREADS");
  if (!text || !*text) return cpus;
  char* end = nullptr;
  const long value = std::strtol(text, &end, 10);  // "4" or the first of a nested list, "4,2"
  if (end == text || (*end != '\0' && *end != ',') || value < 1) return cpus;
  return static_cast<int>(std::min<long>(value, static_cast<long>(kMaxThreadsPerCpu) * cpus));
}

int checked_thread_count(int requested, const std::string& where) {
  const int cpus = available_cpus();
  if (requested < 0)
    throw Error(where, fmt::format("expected a thread count >= 0 (0: all {} CPUs), got {}", cpus, requested));
  if (requested == 0) return default_thread_count();
  const int limit = kMaxThreadsPerCpu * cpus;
  if (requested > limit)
    throw Error(where, fmt::format("{} threads is more than {} ({} per CPU; this process may use {} CPUs); "
                                   "0 uses every CPU",
                                   requested, limit, kMaxThreadsPerCpu, cpus));
  return requested;
}

}  // namespace retarget
