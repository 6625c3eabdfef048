#include "core/random.h"

#include <c10/util/Exception.h>

#include <cmath>
#include <limits>

namespace retarget {

uint64_t Random::below(uint64_t n) {
  TORCH_CHECK(n >= 1, "Random::below: n must be at least 1");
  constexpr uint64_t kMax = std::numeric_limits<uint64_t>::max();
  // [0, limit) holds a whole number of blocks of n values.
  const uint64_t limit = kMax - kMax % n;
  uint64_t x = next();
  while (x >= limit) x = next();
  return x % n;
}

double Random::normal() {
  constexpr double kTwoPi = 6.283185307179586476925286766559;
  const double u1 = unit();
  const double u2 = static_cast<double>(next() >> 11) * 0x1.0p-53;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(kTwoPi * u2);
}

std::vector<int64_t> Random::permutation(int64_t n) {
  TORCH_CHECK(n >= 0, "Random::permutation: n must be >= 0, got ", n);
  std::vector<int64_t> order(static_cast<size_t>(n));
  for (int64_t i = 0; i < n; ++i) order[static_cast<size_t>(i)] = i;
  shuffle(order);
  return order;
}

uint64_t mix_seed(uint64_t seed, uint64_t stream, uint64_t index) {
  uint64_t z = seed * 0x9E3779B97F4A7C15ULL + stream * 0xBF58476D1CE4E5B9ULL + index * 0x94D049BB133111EBULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

}  // namespace retarget
