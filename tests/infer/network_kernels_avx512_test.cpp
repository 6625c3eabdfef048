// The AVX-512 loops of the native network against plain loops that say what each computes, on
// widths with and without a partial last register (1, 9, 16, 64, 72, 192, 200).
#include "infer/network_kernels_avx512.h"

// LibTorch before Catch: glog (through c10) defines CHECK, and the last definition wins.
#include <torch/torch.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace retarget::native_network_kernels {
namespace {

const int64_t kWidths[] = {1, 9, 16, 64, 72, 192, 200};

// Whether the kernels run on this CPU; where they do not, the check must say so because the CPU
// lacks AVX-512 (the native network then takes its portable loops, which tests/infer's
// retargeter tests cover).
bool runs_here() {
  if (avx512_kernels_available()) return true;
  CHECK_FALSE(__builtin_cpu_supports("avx512f"));
  return false;
}

std::vector<float> random_floats(int64_t n, std::mt19937& rng, float spread = 3.0f) {
  std::uniform_real_distribution<float> u(-spread, spread);
  std::vector<float> x(static_cast<size_t>(n));
  for (float& v : x) v = u(rng);
  return x;
}

TEST_CASE("AVX-512 quantisation: each row in 8 bits about its own largest magnitude", "[network_kernels]") {
  if (!runs_here()) return;
  std::mt19937 rng(3);
  for (const int64_t k : kWidths) {
    INFO("width " << k);
    const int64_t rows = 5;
    std::vector<float> x = random_floats(rows * k, rng);
    std::fill_n(x.begin() + 2 * k, k, 0.0f);  // a row of zeros has scale 1
    x[static_cast<size_t>(k - 1)] = -7.5f;    // the largest magnitude is negative, in the last lane
    std::vector<uint8_t> q(static_cast<size_t>(rows * k) + 16, 0xAB);  // past the end: untouched
    std::vector<float> scale(rows);
    quantise_rows_avx512(x.data(), rows, k, q.data(), scale.data());
    CHECK(scale[0] == 7.5f / 127.0f);
    CHECK(scale[2] == 1.0f);
    for (int64_t r = 0; r < rows; ++r) {
      float top = 0;
      for (int64_t c = 0; c < k; ++c) top = std::max(top, std::abs(x[r * k + c]));
      CHECK(scale[r] == (top > 0 ? top / 127.0f : 1.0f));
      for (int64_t c = 0; c < k; ++c) {
        const float expected = x[r * k + c] / scale[r] + 128.0f;
        const int value = q[static_cast<size_t>(r * k + c)];
        CHECK(value >= 1);
        CHECK(value <= 255);
        CHECK(std::abs(value - expected) <= 0.5f + 1e-4f);
      }
    }
    CHECK(q[static_cast<size_t>(rows * k)] == 0xAB);
  }
}

TEST_CASE("AVX-512 epilogue of 8-bit products: scaled, biased and activated", "[network_kernels]") {
  if (!runs_here()) return;
  std::mt19937 rng(5);
  std::uniform_int_distribution<int32_t> sums(-200000, 200000);
  const float slope = 0.1f;
  for (const int64_t n : kWidths) {
    INFO("width " << n);
    const int64_t m = 3;
    std::vector<int32_t> acc(static_cast<size_t>(m * n));
    for (int32_t& a : acc) a = sums(rng);
    const std::vector<float> a_scale = random_floats(m, rng, 1e-3f), w_scale = random_floats(n, rng, 1e-3f),
                             bias = random_floats(n, rng);
    for (const bool leaky : {false, true})
      for (const bool biased : {false, true}) {
        std::vector<float> c(static_cast<size_t>(m * n) + 1, -99.0f);
        scale_sums_avx512(acc.data(), a_scale.data(), m, w_scale.data(), n, biased ? bias.data() : nullptr, leaky,
                          slope, c.data());
        for (int64_t r = 0; r < m; ++r)
          for (int64_t j = 0; j < n; ++j) {
            float y = static_cast<float>(acc[r * n + j]) * (a_scale[r] * w_scale[j]) + (biased ? bias[j] : 0.0f);
            if (leaky && y <= 0) y *= slope;
            CHECK(std::abs(c[r * n + j] - y) <= 1e-6f * (1 + std::abs(y)));
          }
        CHECK(c[static_cast<size_t>(m * n)] == -99.0f);
      }
  }
}

TEST_CASE("AVX-512 sparse rows: the weighted sum of the rows an operator row names", "[network_kernels]") {
  if (!runs_here()) return;
  std::mt19937 rng(7);
  const int64_t source_rows = 11;
  const std::vector<int64_t> columns = {4, 0, 10, 4, 7};  // a repeated column counts twice
  const std::vector<float> values = {0.5f, -1.25f, 2.0f, 0.75f, -0.1f};
  for (const int64_t n : kWidths) {
    INFO("width " << n);
    const int64_t row = n + 3;  // rows further apart than they are wide
    const std::vector<float> src = random_floats(source_rows * row, rng);
    for (int64_t count = 0; count <= static_cast<int64_t>(columns.size()); ++count) {
      std::vector<float> dst(static_cast<size_t>(n) + 1, -99.0f);
      weighted_rows_avx512(columns.data(), values.data(), count, src.data(), row, dst.data(), n);
      for (int64_t c = 0; c < n; ++c) {
        float expected = 0;
        for (int64_t j = 0; j < count; ++j) expected += values[j] * src[columns[j] * row + c];
        CHECK(std::abs(dst[c] - expected) <= 1e-5f);
      }
      CHECK(dst[static_cast<size_t>(n)] == -99.0f);
    }
    // A step of Clenshaw's recurrence: the sums plus one row, minus another, then LeakyReLU.
    const std::vector<float> add = random_floats(n, rng), sub = random_floats(n, rng);
    for (const bool leaky : {false, true})
      for (const bool subtracts : {false, true}) {
        std::vector<float> dst(static_cast<size_t>(n) + 1, -99.0f);
        const RowStep step{add.data(), subtracts ? sub.data() : nullptr, leaky, 0.1f};
        weighted_rows_avx512(columns.data(), values.data(), 5, src.data(), row, dst.data(), n, step);
        for (int64_t c = 0; c < n; ++c) {
          float expected = add[c] - (subtracts ? sub[c] : 0.0f);
          for (int64_t j = 0; j < 5; ++j) expected += values[j] * src[columns[j] * row + c];
          if (leaky && expected <= 0) expected *= 0.1f;
          CHECK(std::abs(dst[c] - expected) <= 1e-5f);
        }
        CHECK(dst[static_cast<size_t>(n)] == -99.0f);
      }
  }
}

}  // namespace
}  // namespace retarget::native_network_kernels
