#include "infer/network_kernels_avx512.h"

#include <immintrin.h>

#include <cstring>

// GCC 12 reports the intrinsics' own _mm512_undefined_*() placeholders as "may be used
// uninitialized" wherever they are inlined; nothing here reads an undefined value.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

namespace retarget::native_network_kernels {

namespace {

constexpr int64_t kLanes = 16;  // floats in a zmm register

__attribute__((target("avx512f"))) inline __mmask16 tail_mask(int64_t left) {
  return static_cast<__mmask16>(left >= kLanes ? 0xffff : (1u << left) - 1u);
}

}  // namespace

bool avx512_kernels_available() {
  static const bool available = __builtin_cpu_supports("avx512f") != 0;
  return available;
}

__attribute__((target("avx512f"))) void quantise_rows_avx512(const float* x, int64_t rows, int64_t k, uint8_t* q,
                                                             float* scale) {
  for (int64_t r = 0; r < rows; ++r) {
    const float* row = x + r * k;
    const __m512i magnitude = _mm512_set1_epi32(0x7fffffff);  // clears the sign bit
    __m512i top = _mm512_setzero_si512();                     // non-negative floats order as their bits do
    for (int64_t c = 0; c < k; c += kLanes)
      top = _mm512_max_epi32(top, _mm512_and_si512(_mm512_maskz_loadu_epi32(tail_mask(k - c), row + c), magnitude));
    const int32_t top_bits = _mm512_reduce_max_epi32(top);  // a tree of shuffles, not 16 dependent maxima
    float largest;
    std::memcpy(&largest, &top_bits, sizeof largest);
    const float s = largest > 0 ? largest / 127.0f : 1.0f, inverse = 1.0f / s;
    scale[r] = s;
    const __m512 times = _mm512_set1_ps(inverse), shift = _mm512_set1_ps(128.5f);
    uint8_t* out = q + r * k;
    for (int64_t c = 0; c < k; c += kLanes) {
      const __mmask16 m = tail_mask(k - c);
      const __m512 v = _mm512_add_ps(_mm512_mul_ps(_mm512_maskz_loadu_ps(m, row + c), times), shift);
      _mm512_mask_cvtepi32_storeu_epi8(out + c, m, _mm512_cvttps_epi32(v));
    }
  }
}

__attribute__((target("avx512f"))) void scale_sums_avx512(const int32_t* acc, const float* a_scale, int64_t m,
                                                          const float* w_scale, int64_t n, const float* bias,
                                                          bool leaky, float slope, float* c) {
  const __m512 slopes = _mm512_set1_ps(slope);
  for (int64_t r = 0; r < m; ++r) {
    const __m512 s = _mm512_set1_ps(a_scale[r]);
    const int32_t* sums = acc + r * n;
    float* out = c + r * n;
    for (int64_t j = 0; j < n; j += kLanes) {
      const __mmask16 mask = tail_mask(n - j);
      const __m512 w = _mm512_mul_ps(s, _mm512_maskz_loadu_ps(mask, w_scale + j));
      __m512 y = _mm512_mul_ps(_mm512_cvtepi32_ps(_mm512_maskz_loadu_epi32(mask, sums + j)), w);
      if (bias) y = _mm512_add_ps(y, _mm512_maskz_loadu_ps(mask, bias + j));
      // LeakyReLU: y where y > 0, else slope * y.
      if (leaky) y = _mm512_mask_mul_ps(y, _mm512_cmp_ps_mask(y, _mm512_setzero_ps(), _CMP_LE_OQ), y, slopes);
      _mm512_mask_storeu_ps(out + j, mask, y);
    }
  }
}

namespace {

// Stores act(sum + add - sub) for 16 floats at offset c (masked by m); add and sub may be null.
__attribute__((target("avx512f"))) inline void store_step(__m512 sum, const RowStep& step, int64_t c, __mmask16 m,
                                                          float* dst) {
  if (step.add) sum = _mm512_add_ps(sum, _mm512_maskz_loadu_ps(m, step.add + c));
  if (step.sub) sum = _mm512_sub_ps(sum, _mm512_maskz_loadu_ps(m, step.sub + c));
  if (step.leaky)
    sum = _mm512_mask_mul_ps(sum, _mm512_cmp_ps_mask(sum, _mm512_setzero_ps(), _CMP_LE_OQ), sum,
                             _mm512_set1_ps(step.slope));
  _mm512_mask_storeu_ps(dst + c, m, sum);
}

}  // namespace

__attribute__((target("avx512f"))) void weighted_rows_avx512(const int64_t* columns, const float* values, int64_t count,
                                                             const float* src, int64_t src_row, float* dst, int64_t n,
                                                             const RowStep& step) {
  int64_t c0 = 0;
  for (; c0 + 4 * kLanes <= n; c0 += 4 * kLanes) {  // 64 floats in four registers
    __m512 a0 = _mm512_setzero_ps(), a1 = a0, a2 = a0, a3 = a0;
    __m512 b0 = a0, b1 = a0, b2 = a0, b3 = a0;  // odd entries: two chains of sums hide the FMA latency
    int64_t j = 0;
    for (; j + 2 <= count; j += 2) {
      const __m512 w = _mm512_set1_ps(values[j]), u = _mm512_set1_ps(values[j + 1]);
      const float* s = src + columns[j] * src_row + c0;
      const float* t = src + columns[j + 1] * src_row + c0;
      a0 = _mm512_fmadd_ps(w, _mm512_loadu_ps(s), a0);
      a1 = _mm512_fmadd_ps(w, _mm512_loadu_ps(s + kLanes), a1);
      a2 = _mm512_fmadd_ps(w, _mm512_loadu_ps(s + 2 * kLanes), a2);
      a3 = _mm512_fmadd_ps(w, _mm512_loadu_ps(s + 3 * kLanes), a3);
      b0 = _mm512_fmadd_ps(u, _mm512_loadu_ps(t), b0);
      b1 = _mm512_fmadd_ps(u, _mm512_loadu_ps(t + kLanes), b1);
      b2 = _mm512_fmadd_ps(u, _mm512_loadu_ps(t + 2 * kLanes), b2);
      b3 = _mm512_fmadd_ps(u, _mm512_loadu_ps(t + 3 * kLanes), b3);
    }
    if (j < count) {
      const __m512 w = _mm512_set1_ps(values[j]);
      const float* s = src + columns[j] * src_row + c0;
      a0 = _mm512_fmadd_ps(w, _mm512_loadu_ps(s), a0);
      a1 = _mm512_fmadd_ps(w, _mm512_loadu_ps(s + kLanes), a1);
      a2 = _mm512_fmadd_ps(w, _mm512_loadu_ps(s + 2 * kLanes), a2);
      a3 = _mm512_fmadd_ps(w, _mm512_loadu_ps(s + 3 * kLanes), a3);
    }
    const __mmask16 all = 0xffff;
    store_step(_mm512_add_ps(a0, b0), step, c0, all, dst);
    store_step(_mm512_add_ps(a1, b1), step, c0 + kLanes, all, dst);
    store_step(_mm512_add_ps(a2, b2), step, c0 + 2 * kLanes, all, dst);
    store_step(_mm512_add_ps(a3, b3), step, c0 + 3 * kLanes, all, dst);
  }
  for (; c0 < n; c0 += kLanes) {  // the rest, 16 at a time (the last masked)
    const __mmask16 m = tail_mask(n - c0);
    __m512 a = _mm512_setzero_ps();
    for (int64_t j = 0; j < count; ++j)
      a = _mm512_fmadd_ps(_mm512_set1_ps(values[j]), _mm512_maskz_loadu_ps(m, src + columns[j] * src_row + c0), a);
    store_step(a, step, c0, m, dst);
  }
}

}  // namespace retarget::native_network_kernels
