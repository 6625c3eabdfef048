#include "core/random.h"

#include <c10/util/Exception.h>

#include <algorithm>
#include <bitset>
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <numeric>
#include <string>
#include <vector>

namespace retarget {
namespace {

// The pinned values below come from an independent Python implementation of mt19937_64 (the
// standard's recurrence and tempering) and of the mappings the header writes out. A change here
// changes datasets' splits, rigs' samples, tournament brackets and training runs.

TEST_CASE("next() is the standard's mt19937_64", "[random]") {
  // [rand.predef]: the 10000th output of a default-constructed mt19937_64 (seed 5489).
  Random standard(5489);
  for (int i = 0; i < 9999; ++i) standard.next();
  CHECK(standard.next() == 9981545732273789042ull);
  Random r(1);
  CHECK(r.next() == 2469588189546311528ull);
  CHECK(r.next() == 2516265689700432462ull);
  CHECK(r.next() == 8323445853463659930ull);
}

TEST_CASE("below(n) is pinned, in range and unbiased", "[random]") {
  Random r(1);
  const std::vector<uint64_t> got = {r.below(1),  r.below(2),    r.below(3),
                                     r.below(10), r.below(1000), r.below((1ull << 63) + 5)};
  CHECK(got == std::vector<uint64_t>{0, 0, 0, 6, 384, 8683844110200328628ull});
  Random dice(42);
  std::vector<uint64_t> rolls;
  for (int i = 0; i < 8; ++i) rolls.push_back(dice.below(6));
  CHECK(rolls == std::vector<uint64_t>{0, 2, 4, 0, 5, 2, 4, 0});

  // 60,000 rolls of a die: each face 10,000 +- 4.5 sigma (sigma = 91).
  std::vector<int> counts(6, 0);
  for (int i = 0; i < 60000; ++i) {
    const uint64_t face = dice.below(6);
    REQUIRE(face < 6);
    ++counts[face];
  }
  for (int c : counts) CHECK(std::abs(c - 10000) < 410);
  CHECK_THROWS_AS(dice.below(0), c10::Error);
}

TEST_CASE("unit() is in (0, 1], uniform() in (lo, hi], both pinned", "[random]") {
  Random r(1);
  CHECK(r.unit() == 0.13387664401253274);
  CHECK(r.unit() == 0.13640703636619733);
  CHECK(r.unit() == 0.4512149038445382);
  Random a(9), b(9);
  double lowest = 1, highest = 0, sum = 0;
  for (int i = 0; i < 100000; ++i) {
    const double u = a.unit();
    CHECK(b.uniform(-2.0, 3.0) == -2.0 + u * 5.0);
    lowest = std::min(lowest, u);
    highest = std::max(highest, u);
    sum += u;
  }
  CHECK(lowest > 0);
  CHECK(lowest < 1e-3);
  CHECK(highest <= 1);
  CHECK(highest > 1 - 1e-3);
  CHECK(sum / 100000 == Approx(0.5).margin(0.005));  // sigma of the mean: 0.0009
}

TEST_CASE("normal() is pinned, costs two draws and has mean 0 and variance 1", "[random]") {
  Random r(1);
  // Through std::log and std::cos: exact up to the maths library's last bit.
  for (double expected : {1.312851528985562, 1.2506039211781217, 1.2285219999610564, 1.0957496171508985})
    CHECK(r.normal() == Approx(expected).epsilon(1e-14));
  Random mixed(3);
  CHECK(mixed.unit() == 0.5587659896231791);
  CHECK(mixed.normal() == Approx(-1.5234008835184736).epsilon(1e-14));
  CHECK(mixed.below(100) == 29);
  CHECK(mixed.next() == 10326406840904628101ull);

  Random g(5);
  const int n = 200000;
  double sum = 0, squares = 0, fourth = 0;
  for (int i = 0; i < n; ++i) {
    const double x = g.normal();
    REQUIRE(std::isfinite(x));
    sum += x;
    squares += x * x;
    fourth += x * x * x * x;
  }
  CHECK(sum / n == Approx(0).margin(0.01));       // sigma 0.0022
  CHECK(squares / n == Approx(1).margin(0.015));  // sigma 0.0032
  CHECK(fourth / n == Approx(3).margin(0.1));     // a normal's kurtosis; sigma ~0.022
}

TEST_CASE("shuffle is Fisher-Yates over below(): pinned, a permutation, every order alike", "[random]") {
  Random r(1);
  CHECK(r.permutation(10) == std::vector<int64_t>{1, 7, 3, 9, 4, 0, 5, 2, 6, 8});
  Random letters(7);
  CHECK(letters.shuffled(std::vector<std::string>{"a", "b", "c", "d", "e"}) ==
        std::vector<std::string>{"b", "d", "e", "c", "a"});

  // shuffle, shuffled and permutation are one algorithm.
  std::vector<int> in_place(50);
  std::iota(in_place.begin(), in_place.end(), 0);
  Random a(11), b(11), c(11);
  const std::vector<int> copy = b.shuffled(in_place);
  a.shuffle(in_place);
  CHECK(in_place == copy);
  const std::vector<int64_t> order = c.permutation(50);
  CHECK(std::equal(order.begin(), order.end(), copy.begin()));
  std::vector<int> sorted = copy;
  std::sort(sorted.begin(), sorted.end());
  for (int i = 0; i < 50; ++i) CHECK(sorted[static_cast<size_t>(i)] == i);

  Random e(0);
  CHECK(e.permutation(0).empty());
  CHECK(e.permutation(1) == std::vector<int64_t>{0});
  CHECK_THROWS_AS(e.permutation(-1), c10::Error);

  // 24,000 shuffles of 4 items: each of the 24 orders 1,000 +- 5 sigma (sigma = 31).
  std::map<std::vector<int64_t>, int> seen;
  Random s(2);
  for (int i = 0; i < 24000; ++i) ++seen[s.permutation(4)];
  CHECK(seen.size() == 24);
  for (const auto& [permutation, count] : seen) CHECK(std::abs(count - 1000) < 160);
}

TEST_CASE("mix_seed: pinned, and nearby inputs give unrelated seeds", "[random]") {
  CHECK(mix_seed(1, 0) == 16294208416658607535ull);
  CHECK(mix_seed(1, 1) == 16481712997681181849ull);
  CHECK(mix_seed(1, 1, 0) == mix_seed(1, 1));
  CHECK(mix_seed(1, 2, 3) == 13415167193062074755ull);
  CHECK(mix_seed(1, 4, 7) == 136673221444711495ull);
  CHECK(mix_seed(2, 1) == 4560642061891045783ull);
  // Neighbours in any argument differ in about half of their 64 bits.
  for (uint64_t k = 0; k < 64; ++k) {
    const uint64_t base = mix_seed(k, 3, k);
    for (const uint64_t other : {mix_seed(k + 1, 3, k), mix_seed(k, 4, k), mix_seed(k, 3, k + 1)}) {
      const size_t differing = std::bitset<64>(base ^ other).count();
      CHECK(differing > 12);
      CHECK(differing < 52);
    }
  }
}

}  // namespace
}  // namespace retarget
