// AVX-512 loops of the native network (infer/retargeter_network.cpp), written with intrinsics
// where the compiler's own vectorisation falls short (issue 32's profile): the row maxima of
// 8-bit quantisation (GCC keeps `a < b ? b : a` scalar), the int32 -> float epilogue of the 8-bit
// products, and the sparse rows' weighted sums kept in registers instead of stored and reloaded
// per operator entry. Each computes what its portable counterpart in retargeter_network.cpp
// computes; the sparse sums add even and odd operator entries in two chains (each in order), so
// their rounding differs from the portable loops' (tests/infer bounds both against the script).
// Call them only where avx512_kernels_available().
#pragma once

#include <cstdint>

namespace retarget::native_network_kernels {

// Whether this CPU runs the kernels below (AVX-512 F).
bool avx512_kernels_available();

// Each of `rows` rows of x [rows, k] to u8 about 128: q = trunc(x / scale + 128.5), scale[r] =
// max |x(r, :)| / 127 (1 for a row of zeros), q in [1, 255].
void quantise_rows_avx512(const float* x, int64_t rows, int64_t k, uint8_t* q, float* scale);

// c [m, n] = act(acc [m, n] * (a_scale[r] * w_scale[j]) + bias[j]), act = LeakyReLU(slope) when
// `leaky`, else none; bias may be null.
void scale_sums_avx512(const int32_t* acc, const float* a_scale, int64_t m, const float* w_scale, int64_t n,
                       const float* bias, bool leaky, float slope, float* c);

// What follows a sparse row's sums while they are in registers (a step of Clenshaw's recurrence):
// + add[0, n), - sub[0, n) (each where not null), then LeakyReLU(slope) where `leaky`.
struct RowStep {
  const float* add = nullptr;
  const float* sub = nullptr;
  bool leaky = false;
  float slope = 0;
};

// dst[0, n) = step(sum over j < count of values[j] * src[columns[j] * src_row + [0, n)]), the sum
// of even and of odd entries each in order, then added.
void weighted_rows_avx512(const int64_t* columns, const float* values, int64_t count, const float* src, int64_t src_row,
                          float* dst, int64_t n, const RowStep& step = {});

}  // namespace retarget::native_network_kernels
