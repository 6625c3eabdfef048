#include "core/cpu_threads.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdlib>
#include <string>

#include "core/error.h"

namespace retarget {
namespace {

TEST_CASE("thread counts: 0 is every CPU, the bound is per CPU, the message says both", "[cpu_threads]") {
  ::unsetenv("OMP_NUM_THREADS");
  const int cpus = available_cpus();
  CHECK(cpus >= 1);
  CHECK(checked_thread_count(0, "--threads") == cpus);
  CHECK(checked_thread_count(1, "--threads") == 1);
  CHECK(checked_thread_count(kMaxThreadsPerCpu * cpus, "--threads") == kMaxThreadsPerCpu * cpus);
  CHECK_THROWS_WITH(checked_thread_count(kMaxThreadsPerCpu * cpus + 1, "training.threads"),
                    Catch::StartsWith("training.threads: " + std::to_string(kMaxThreadsPerCpu * cpus + 1) +
                                      " threads is more than " + std::to_string(kMaxThreadsPerCpu * cpus)) &&
                        Catch::Contains("may use " + std::to_string(cpus) + " CPUs"));
  CHECK_THROWS_WITH(checked_thread_count(100000, "--threads"), Catch::Contains("100000 threads"));
  CHECK_THROWS_WITH(checked_thread_count(-2, "--threads"),
                    Catch::StartsWith("--threads: expected a thread count >= 0") && Catch::Contains("got -2"));
}

TEST_CASE("thread counts: 0 follows OMP_NUM_THREADS when it is set, as schedulers set it", "[cpu_threads]") {
  const int cpus = available_cpus();
  ::setenv("OMP_NUM_THREADS", "1", 1);
  CHECK(checked_thread_count(0, "--threads") == 1);
  CHECK(checked_thread_count(3, "--threads") == 3);  // an explicit count wins
  ::setenv("OMP_NUM_THREADS", "2,1", 1);
  CHECK(default_thread_count() == std::min(2, kMaxThreadsPerCpu * cpus));
  ::setenv("OMP_NUM_THREADS", "100000", 1);
  CHECK(default_thread_count() == kMaxThreadsPerCpu * cpus);
  for (const char* junk : {"", "zero", "-3", "0", "2x"}) {
    ::setenv("OMP_NUM_THREADS", junk, 1);
    CHECK(default_thread_count() == cpus);
  }
  ::unsetenv("OMP_NUM_THREADS");
  CHECK(default_thread_count() == cpus);
}

}  // namespace
}  // namespace retarget
