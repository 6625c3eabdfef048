#include "core/parallel_for.h"

#include <atomic>
#include <catch2/catch.hpp>
#include <stdexcept>
#include <vector>

using namespace retarget;

TEST_CASE("parallel_for runs every item once, and rethrows the first failure by item order", "[core]") {
  std::vector<std::atomic<int>> runs(100);
  parallel_for(100, [&](int i) { ++runs[static_cast<size_t>(i)]; });
  for (const std::atomic<int>& r : runs) CHECK(r.load() == 1);

  std::atomic<int> done{0};
  CHECK_THROWS_WITH(parallel_for(50,
                                 [&](int i) {
                                   ++done;
                                   if (i == 7 || i == 31) throw std::runtime_error("item " + std::to_string(i));
                                 }),
                    "item 7");
  CHECK(done.load() == 50);  // the items after a failure still ran
  parallel_for(0, [](int) { FAIL("no item to run"); });
}
