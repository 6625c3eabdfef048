// Seeded randomness, the same on every machine, compiler and standard library: one generator
// (Random) and one seed mixer (mix_seed) for the whole code base.
//
// The reproducibility contract:
// - The engine is std::mt19937_64, whose output the C++ standard fixes bit for bit. The standard
//   does not fix what std::uniform_int_distribution, std::normal_distribution or std::shuffle
//   make of it (libstdc++, libc++ and MSVC differ), so none of them is used anywhere: every
//   mapping here is our own, written out below, and tests/core/random_test.cpp pins its values
//   against an independent implementation.
// - Each call draws a fixed number of raw outputs from the engine: next(), unit() and uniform()
//   one, normal() two, below(n) one (another only on a rejection, which happens with probability
//   below n / 2^64), shuffle() of n elements n - 1 calls of below(). A sequence of calls is
//   therefore a function of the seed alone, and a generator re-made from its seed continues
//   exactly where an interrupted one would have.
// - The integers, unit(), uniform() and shuffles are exact. normal() also goes through std::log
//   and std::cos, which the standard does not require to be correctly rounded: across maths
//   libraries it may differ in the last bit or so.
// - These numbers decide a dataset's split, a rig's samples, a tournament's bracket and the
//   batches of a training run. Changing a mapping changes all of those, which is why the values
//   are pinned.
// - LibTorch's own generator (initialisation, torch::randn) is not this one: the trainers seed it
//   with torch::manual_seed(mix_seed(...)), and the numbers it then produces are LibTorch's.
// - Not for secrets: the annotation server's session tokens come from std::random_device.
// - Not thread-safe: one Random per thread and per purpose. Purposes get seeds of their own from
//   mix_seed, so that drawing more for one never moves the numbers of another.
#pragma once

#include <cstdint>
#include <random>
#include <utility>
#include <vector>

namespace retarget {

class Random {
 public:
  // Any seed is fine, 0 included (mt19937_64's own seeding spreads it over the state).
  explicit Random(uint64_t seed) : engine_(seed) {}

  // The engine's next raw 64-bit output.
  uint64_t next() { return engine_(); }

  // Uniform in {0, ..., n - 1}: next() % n, drawing again while next() falls in the last,
  // incomplete block of n values (so no value is favoured). n >= 1 (TORCH_CHECK).
  uint64_t below(uint64_t n);

  // Uniform in (0, 1]: the top 53 bits of next(), plus one step, times 2^-53. Never 0, so that a
  // logarithm of it is finite.
  double unit() { return static_cast<double>((next() >> 11) + 1) * 0x1.0p-53; }

  // Uniform in (lo, hi]: lo + unit() * (hi - lo).
  double uniform(double lo, double hi) { return lo + unit() * (hi - lo); }

  // Standard normal by Box-Muller: sqrt(-2 ln u1) cos(2 pi u2), u1 = unit() in (0, 1] first,
  // then u2 = (next() >> 11) 2^-53 in [0, 1). The sine of the pair is not kept, so every call
  // costs exactly two draws.
  double normal();

  // Fisher-Yates: for i = n - 1 down to 1, swap values[i] with values[below(i + 1)]. Every order
  // equally likely; the same order for the same seed on every standard library (unlike
  // std::shuffle).
  template <class T>
  void shuffle(std::vector<T>& values) {
    for (size_t i = values.size(); i > 1; --i) {
      using std::swap;
      swap(values[i - 1], values[static_cast<size_t>(below(i))]);
    }
  }

  // A shuffled copy of `values` (shuffle()).
  template <class T>
  std::vector<T> shuffled(std::vector<T> values) {
    shuffle(values);
    return values;
  }

  // 0, ..., n - 1 in shuffled order (shuffle() of the ascending sequence). n >= 0.
  std::vector<int64_t> permutation(int64_t n);

 private:
  std::mt19937_64 engine_;
};

// The seed of one purpose: `stream` names the purpose (each caller keeps its own named
// constants), `index` the repetition (an epoch, a group). The splitmix64 finaliser of
// seed * 0x9E3779B97F4A7C15 + stream * 0xBF58476D1CE4E5B9 + index * 0x94D049BB133111EB (mod 2^64),
// so nearby seeds, streams and indices give unrelated generators. Re-seeding from it every epoch
// is what makes a resumed training run bit-identical to an uninterrupted one.
uint64_t mix_seed(uint64_t seed, uint64_t stream, uint64_t index = 0);

}  // namespace retarget
