#include "core/parallel_for.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <thread>
#include <vector>

#include "core/cpu_threads.h"

namespace retarget {

void parallel_for(int count, const std::function<void(int)>& work) {
  if (count <= 0) return;
  std::atomic<int> next{0};
  std::vector<std::exception_ptr> failures(static_cast<size_t>(count));
  auto run = [&] {
    for (int i = next++; i < count; i = next++) {
      try {
        work(i);
      } catch (...) {
        failures[static_cast<size_t>(i)] = std::current_exception();
      }
    }
  };
  const int workers = std::clamp(available_cpus(), 1, count);
  std::vector<std::thread> pool;
  for (int w = 1; w < workers; ++w) pool.emplace_back(run);
  run();
  for (std::thread& t : pool) t.join();
  for (const std::exception_ptr& failure : failures)
    if (failure) std::rethrow_exception(failure);
}

}  // namespace retarget
