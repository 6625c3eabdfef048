#include "infer/retargeter_network.h"

#include <ATen/Parallel.h>
#include <dlfcn.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>

#include "bundle/normalisation.h"
#include "infer/network_kernels_avx512.h"
#include "infer/onednn_isa.h"

namespace retarget {

namespace native_network_kernels {

// GEMM rows of a block (vertices x samples): with 192 terms a row ~0.4 MB, so the block, its
// product and most rows it gathers stay in one core's 2 MB L2.
constexpr int64_t kBlockRows = 512;

// Element (v, b, 0) of a [V, B, C]-like signal at data + (v - first) * row + b * sample.
struct Signal {
  float* data = nullptr;
  int64_t row = 0, sample = 0, first = 0;
  float* at(int64_t v, int64_t b) const { return data + (v - first) * row + b * sample; }
};

Signal whole(const torch::Tensor& t, int64_t batch, int64_t channels) {
  return {t.data_ptr<float>(), batch * channels, channels, 0};
}

struct Operator {
  const int64_t* offsets;  // [V + 1]
  const int64_t* columns;
  const float* values;
};

// dst[c0, n) = sum over j < count (in order) of values[j] * src[columns[j] * src_row + [c0, n)],
// `width` floats at a time in registers (no store and reload per entry: short rows would wait on
// them); returns where it stopped.
template <int64_t width>
inline int64_t accumulate(const int64_t* columns, const float* values, int64_t count, const float* src, int64_t src_row,
                          float* dst, int64_t c0, int64_t n) {
  for (; c0 + width <= n; c0 += width) {
    float acc[width] = {};
    for (int64_t j = 0; j < count; ++j) {
      const float w = values[j];
      const float* s = src + columns[j] * src_row + c0;
      for (int64_t c = 0; c < width; ++c) acc[c] += w * s[c];
    }
    std::copy_n(acc, width, dst + c0);
  }
  return c0;
}

// dst(b, :) = sum over the row's entries j (in order) of values[j] * src(columns[j], b, :) for
// b < batch: the sums of torch.embedding_bag (mode sum, per-sample weights) over the signal viewed
// [V, B * C], in the same order (on CPUs with AVX-512: weighted_rows_avx512, even and odd entries in
// two chains). Compiled for AVX-512 and AVX2 too, picked at load.
__attribute__((target_clones("avx512f", "avx2", "default"))) void gather_row(
    const int64_t* columns, const float* values, int64_t count, const float* src, int64_t src_row, int64_t src_sample,
    float* dst, int64_t dst_sample, int64_t batch, int64_t channels) {
  const bool whole_rows = batch == 1 || (src_sample == channels && dst_sample == channels);
  const int64_t segments = whole_rows ? 1 : batch, n = whole_rows ? batch * channels : channels;
  const bool avx512 = avx512_kernels_available();
  for (int64_t b = 0; b < segments; ++b) {
    const float* s = src + b * src_sample;
    float* d = dst + b * dst_sample;
    if (avx512) {  // sums in registers, 64 floats at a time
      weighted_rows_avx512(columns, values, count, s, src_row, d, n);
      continue;
    }
    if (n >= 64) {  // long rows: the entries' loads and stores overlap well enough
      std::fill_n(d, n, 0.0f);
      for (int64_t j = 0; j < count; ++j) {
        const float w = values[j];
        const float* sj = s + columns[j] * src_row;
        for (int64_t c = 0; c < n; ++c) d[c] += w * sj[c];
      }
      continue;
    }
    int64_t c0 = accumulate<64>(columns, values, count, s, src_row, d, 0, n);
    c0 = accumulate<16>(columns, values, count, s, src_row, d, c0, n);
    c0 = accumulate<4>(columns, values, count, s, src_row, d, c0, n);
    accumulate<1>(columns, values, count, s, src_row, d, c0, n);
  }
}

// Row v of L~ src into dst(v, :, :) (src.first must be 0).
inline void gather(const Operator& op, const Signal& src, const Signal& dst, int64_t v, int64_t batch,
                   int64_t channels) {
  const int64_t begin = op.offsets[v];
  gather_row(op.columns + begin, op.values + begin, op.offsets[v + 1] - begin, src.data, src.row, src.sample,
             dst.at(v, 0), dst.sample, batch, channels);
}

// Vertices per task of a pass over the operator's rows: about 4,096 floats of output, at least 16.
inline int64_t rows_grain(int64_t batch, int64_t channels) {
  return std::max<int64_t>(16, 4096 / std::max<int64_t>(1, batch * channels));
}

// dst(v, :, :) = (L~ src)(v, :, :) for every vertex, then finish(v, b, dst(v, b, :)); vertices split
// over LibTorch's threads.
template <class Finish>
void sparse_rows(const Operator& op, const Signal& src, const Signal& dst, int64_t vertices, int64_t batch,
                 int64_t channels, const Finish& finish) {
  at::parallel_for(0, vertices, rows_grain(batch, channels), [&](int64_t begin, int64_t end) {
    for (int64_t v = begin; v < end; ++v) {
      gather(op, src, dst, v, batch, channels);
      for (int64_t b = 0; b < batch; ++b) finish(v, b, dst.at(v, b));
    }
  });
}

// oneDNN's sgemm (row-major), which LibTorch's CPU library loads (libdnnl): found at run time, so
// the runtime needs no oneDNN headers; null where this LibTorch has none.
using DnnlSgemm = int (*)(char, char, int64_t, int64_t, int64_t, float, const float*, int64_t, const float*, int64_t,
                          float, float*, int64_t);
DnnlSgemm dnnl_sgemm() {
  static const DnnlSgemm f = reinterpret_cast<DnnlSgemm>(dlsym(RTLD_DEFAULT, "dnnl_sgemm"));
  return f;
}

// c [m, n] = a [m, k] w [n, k]^T, all row-major and contiguous (c's rows ldc apart, ldc = n when 0),
// on the calling thread (oneDNN runs one thread inside a parallel region). Without oneDNN:
// LibTorch's mm (callers then do not run blocks in parallel).
void product(const float* a, int64_t m, int64_t k, const float* w, int64_t n, float* c, int64_t ldc = 0) {
  if (ldc == 0) ldc = n;
  if (const DnnlSgemm f = dnnl_sgemm(); f && f('N', 'T', m, n, k, 1.0f, a, k, w, k, 0.0f, c, ldc) == 0) return;
  torch::Tensor out = torch::from_blob(c, {m, n}, {ldc, 1}, torch::kFloat32);
  at::mm_out(out, torch::from_blob(const_cast<float*>(a), {m, k}, torch::kFloat32),
             torch::from_blob(const_cast<float*>(w), {n, k}, torch::kFloat32).t());
}

// oneDNN's bfloat16 GEMM (bf16 inputs, float32 sums and output), likewise looked up at run time.
using DnnlGemmBf16 = int (*)(char, char, int64_t, int64_t, int64_t, float, const uint16_t*, int64_t, const uint16_t*,
                             int64_t, float, float*, int64_t);
DnnlGemmBf16 dnnl_gemm_bf16() {
  static const DnnlGemmBf16 f = reinterpret_cast<DnnlGemmBf16>(dlsym(RTLD_DEFAULT, "dnnl_gemm_bf16bf16f32"));
  return f;
}

// Whether bfloat16 products are worth having here: the CPU has AVX512-BF16 (oneDNN would emulate
// them elsewhere, slower than float32) and oneDNN's bf16 GEMM answers a probe.
bool bf16_products_available() {
  static const bool available = [] {
    if (!__builtin_cpu_supports("avx512bf16") || !dnnl_gemm_bf16()) return false;
    const uint16_t one = 0x3f80;  // 1.0
    float c = 0;
    return dnnl_gemm_bf16()('N', 'T', 1, 1, 1, 1.0f, &one, 1, &one, 1, 0.0f, &c, 1) == 0 && c == 1.0f;
  }();
  return available;
}

// oneDNN's 8-bit GEMM, likewise looked up at run time: C [m, n] = (A - ao) (B - bo)^T in int32 for
// u8 A [m, k] and s8 B [n, k] (row-major), plus the fixed offset *co.
using DnnlGemmU8s8s32 = int (*)(char, char, char, int64_t, int64_t, int64_t, float, const uint8_t*, int64_t, uint8_t,
                                const int8_t*, int64_t, int8_t, float, int32_t*, int64_t, const int32_t*);
DnnlGemmU8s8s32 dnnl_gemm_int8() {
  static const DnnlGemmU8s8s32 f = reinterpret_cast<DnnlGemmU8s8s32>(dlsym(RTLD_DEFAULT, "dnnl_gemm_u8s8s32"));
  return f;
}

// Whether 8-bit products are worth having here: the CPU has VNNI dot products (AVX512-VNNI; oneDNN
// emulates them elsewhere, no faster than float32) and oneDNN's 8-bit GEMM answers a probe.
bool int8_products_available() {
  static const bool available = [] {
    if (!__builtin_cpu_supports("avx512vnni") || !dnnl_gemm_int8()) return false;
    prefer_vnni_to_amx();  // before oneDNN's first 8-bit kernel: its AMX path is slower here (infer/onednn_isa.h)
    const uint8_t a = 130;
    const int8_t b = 3;
    const int32_t zero = 0;
    int32_t c = 0;
    return dnnl_gemm_int8()('N', 'T', 'F', 1, 1, 1, 1.0f, &a, 1, 128, &b, 1, 0, 0.0f, &c, 1, &zero) == 0 && c == 6;
  }();
  return available;
}

// Each of `rows` rows of x [rows, k] to u8 about 128: q = round(x / scale) + 128 (halves up), scale[r] =
// max |x(r, :)| / 127 (1 for a row of zeros), so q stays in [1, 255].
__attribute__((target_clones("avx512f", "avx2", "default"))) void quantise_rows(const float* x, int64_t rows, int64_t k,
                                                                                uint8_t* q, float* scale) {
  if (avx512_kernels_available()) {  // GCC leaves the maxima below scalar
    quantise_rows_avx512(x, rows, k, q, scale);
    return;
  }
  constexpr int64_t lanes = 16;  // per-lane maxima and conversions in fixed chunks: they vectorise
  for (int64_t r = 0; r < rows; ++r) {
    const float* row = x + r * k;
    float lane_top[lanes] = {};
    int64_t c = 0;
    for (; c + lanes <= k; c += lanes)
      for (int64_t j = 0; j < lanes; ++j) {
        const float a = row[c + j] < 0 ? -row[c + j] : row[c + j];
        lane_top[j] = lane_top[j] < a ? a : lane_top[j];
      }
    float top = 0;
    for (; c < k; ++c) top = std::max(top, std::abs(row[c]));
    for (float t : lane_top) top = std::max(top, t);
    const float s = top > 0 ? top / 127.0f : 1.0f, inverse = 1.0f / s;
    scale[r] = s;
    uint8_t* out = q + r * k;
    // x / scale + 128.5 lies in [1.5, 255.5]: truncation rounds it (halves up).
    for (c = 0; c < k; ++c) out[c] = static_cast<uint8_t>(static_cast<int32_t>(row[c] * inverse + 128.5f));
  }
}

// Weights [n, k] to s8 per output row: w8 = round(w / scale), scale[j] = max |w(j, :)| / 127.
void quantise_weights(const torch::Tensor& w, torch::Tensor& w8, torch::Tensor& scale) {
  scale = (w.abs().amax(1) / 127.0).clamp_min(1e-30).contiguous();
  w8 = (w / scale.unsqueeze(1)).round().clamp(-127, 127).to(torch::kInt8).contiguous();
}

// What follows an 8-bit product in the same pass: nothing, LeakyReLU or tanh (after the bias).
enum class Activation { none, leaky, tanh };

// c [m, n] = act(a [m, k] w [n, k]^T + bias) with a in 8 bits per row (quantise_rows: q, a_scale)
// and w per output (quantise_weights); bias: [n] or null; acc: m x n int32 scratch. The int32
// sums are scaled, biased and activated in one pass. Only if int8_products_available().
__attribute__((target_clones("avx512f", "avx2", "default"))) void product_int8(const uint8_t* q, const float* a_scale,
                                                                               int64_t m, int64_t k, const int8_t* w,
                                                                               const float* w_scale, int64_t n,
                                                                               const float* bias, Activation activation,
                                                                               int32_t* acc, float* c) {
  const int32_t zero = 0;
  const int status = dnnl_gemm_int8()('N', 'T', 'F', m, n, k, 1.0f, q, k, 128, w, k, 0, 0.0f, acc, n, &zero);
  TORCH_CHECK(status == 0, "oneDNN's 8-bit GEMM failed (status ", status, ")");
  const float slope = static_cast<float>(kNativeNetworkSlope);
  if (activation != Activation::tanh && avx512_kernels_available()) {
    scale_sums_avx512(acc, a_scale, m, w_scale, n, bias, activation == Activation::leaky, slope, c);
    return;
  }
  for (int64_t r = 0; r < m; ++r) {
    const float s = a_scale[r];
    float* row = c + r * n;
    const int32_t* sums = acc + r * n;
    for (int64_t j = 0; j < n; ++j) row[j] = static_cast<float>(sums[j]) * (s * w_scale[j]) + (bias ? bias[j] : 0.0f);
    if (activation == Activation::leaky)
      for (int64_t j = 0; j < n; ++j) row[j] = row[j] > 0 ? row[j] : row[j] * slope;
    if (activation == Activation::tanh)
      for (int64_t j = 0; j < n; ++j) row[j] = std::tanh(row[j]);
  }
}

// dst[i] = src[i] rounded to the nearest bfloat16 (ties to even; inputs are finite).
__attribute__((target_clones("avx512f", "avx2", "default"))) void to_bf16(const float* src, int64_t n, uint16_t* dst) {
  for (int64_t i = 0; i < n; ++i) {
    uint32_t bits;
    std::memcpy(&bits, src + i, sizeof bits);
    dst[i] = static_cast<uint16_t>((bits + 0x7fffu + ((bits >> 16) & 1u)) >> 16);
  }
}

// As product, with a and w in bfloat16 (sums in float32); only if bf16_products_available().
void product_bf16(const uint16_t* a, int64_t m, int64_t k, const uint16_t* w, int64_t n, float* c, int64_t ldc = 0) {
  const int status = dnnl_gemm_bf16()('N', 'T', m, n, k, 1.0f, a, k, w, k, 0.0f, c, ldc == 0 ? n : ldc);
  TORCH_CHECK(status == 0, "oneDNN's bfloat16 GEMM failed (status ", status, ")");
}

// Blocks [v0, v1) of `vertices` of about kBlockRows GEMM rows, run as block(v0, v1, buffer) over
// LibTorch's threads (one at a time without oneDNN), each thread with its own scratch buffer of
// `scratch` floats per GEMM row.
template <class Block>
void blocks(int64_t vertices, int64_t batch, int64_t scratch, const Block& block) {
  const int64_t size = std::max<int64_t>(1, kBlockRows / batch), count = (vertices + size - 1) / size;
  at::parallel_for(0, count, dnnl_sgemm() ? 1 : count, [&](int64_t first, int64_t last) {
    std::vector<float> buffer(static_cast<size_t>(std::min(size, vertices) * batch * scratch));
    for (int64_t i = first; i < last; ++i) block(i * size, std::min(vertices, (i + 1) * size), buffer.data());
  });
}

inline float leaky(float x, float slope) { return x > 0 ? x : x * slope; }

// Rows [m, n] of a product: + bias (if any), then tanh (last conv) or LeakyReLU.
__attribute__((target_clones("avx512f", "avx2", "default"))) void finish_product(float* y, int64_t m, int64_t n,
                                                                                 const float* bias, bool last) {
  const float slope = static_cast<float>(kNativeNetworkSlope);
  for (int64_t r = 0; r < m; ++r) {
    float* row = y + r * n;
    if (bias)
      for (int64_t c = 0; c < n; ++c) row[c] += bias[c];
    if (last) {
      for (int64_t c = 0; c < n; ++c) row[c] = std::tanh(row[c]);
    } else {
      for (int64_t c = 0; c < n; ++c) row[c] = leaky(row[c], slope);
    }
  }
}

}  // namespace native_network_kernels

namespace {

using native_network_kernels::Operator;
using native_network_kernels::Signal;
using native_network_kernels::sparse_rows;
using native_network_kernels::whole;

const uint16_t* bf16_data(const torch::Tensor& t) { return reinterpret_cast<const uint16_t*>(t.data_ptr()); }

torch::Tensor float_tensor(const torch::jit::Module& module, const std::string& name) {
  return module.attr(name).toTensor().detach().to(torch::kCPU, torch::kFloat32).contiguous();
}

}  // namespace

std::string network_products_kernel(NetworkPrecision precision) {
  const std::string missing = network_precision_available(precision) ? "" : " (not on this CPU)";
  switch (precision) {
    case NetworkPrecision::bfloat16:
      return "oneDNN dnnl_gemm_bf16bf16f32" + (missing.empty() ? " on " + onednn_isa() : missing);
    case NetworkPrecision::int8:
      return "oneDNN dnnl_gemm_u8s8s32" + (missing.empty() ? " on " + onednn_isa() : missing);
    default:
      return native_network_kernels::dnnl_sgemm() ? "oneDNN dnnl_sgemm" : "LibTorch mm";
  }
}

std::string network_loops_kernel() {
  return native_network_kernels::avx512_kernels_available() ? "AVX-512 intrinsics"
                                                            : "compiler-vectorised loops (AVX2 or baseline)";
}

bool network_precision_available(NetworkPrecision precision) {
  switch (precision) {
    case NetworkPrecision::bfloat16:
      return native_network_kernels::bf16_products_available();
    case NetworkPrecision::int8:
      return native_network_kernels::int8_products_available();
    default:
      return true;
  }
}

std::unique_ptr<NativeNetwork> NativeNetwork::of_bundle(const torch::jit::Module& module, NetworkPrecision precision) {
  const std::string p = "human_";
  for (const char* name : {"laplacian_indices", "laplacian_values", "laplacian_offsets", "normaliser_min",
                           "convs_0_linear_weight", "encoder_hidden_weight", "mean_head_weight"}) {
    if (!module.hasattr(p + name) || !module.attr(p + name).isTensor()) return nullptr;
  }
  if (!module.find_method(p + "normalise")) return nullptr;
  std::unique_ptr<NativeNetwork> e(new NativeNetwork);
  e->module_ = module;
  e->precision_ = network_precision_available(precision) ? precision : NetworkPrecision::float32;
  const torch::Tensor lo = module.attr(p + "normaliser_min").toTensor();
  if (lo.dim() != 2) return nullptr;
  const int64_t v = lo.size(0);
  e->vertices_ = v;

  // The operator: coalesced COO (rows sorted) with each row's first entry in laplacian_offsets.
  const torch::Tensor indices = module.attr(p + "laplacian_indices").toTensor().to(torch::kInt64).contiguous();
  const torch::Tensor offsets = module.attr(p + "laplacian_offsets").toTensor().to(torch::kInt64).contiguous();
  e->values_ = float_tensor(module, p + "laplacian_values");
  if (indices.dim() != 2 || indices.size(0) != 2 || offsets.dim() != 1 || offsets.size(0) != v ||
      e->values_.dim() != 1 || e->values_.size(0) != indices.size(1))
    return nullptr;
  const int64_t nnz = indices.size(1);
  const torch::Tensor rows = indices[0];
  e->columns_ = indices[1].contiguous();
  if (nnz > 0 && (rows.min().item<int64_t>() < 0 || rows.max().item<int64_t>() >= v ||
                  e->columns_.min().item<int64_t>() < 0 || e->columns_.max().item<int64_t>() >= v ||
                  (nnz > 1 && (rows.slice(0, 1) < rows.slice(0, 0, nnz - 1)).any().item<bool>())))
    return nullptr;
  const torch::Tensor counts = torch::bincount(rows, {}, v);
  if (!torch::equal(offsets, (counts.cumsum(0) - counts).to(torch::kInt64))) return nullptr;
  e->offsets_ = torch::cat({offsets, torch::full({1}, nnz, torch::kInt64)});
  e->values2_ = 2.0 * e->values_;  // as the script's values2 (exact)

  // The graph convs: in -> out channels, K + 1 = weight columns / in terms.
  int64_t in = lo.size(1);
  for (int64_t i = 0;; ++i) {
    const std::string name = p + "convs_" + std::to_string(i) + "_linear_";
    if (!module.hasattr(name + "weight")) break;
    Conv conv;
    conv.weight = float_tensor(module, name + "weight");
    if (conv.weight.dim() != 2 || conv.weight.size(1) % in != 0) return nullptr;
    conv.in = in;
    conv.out = conv.weight.size(0);
    conv.order = conv.weight.size(1) / in - 1;
    if (module.hasattr(name + "bias")) {
      if (!module.attr(name + "bias").isTensor()) return nullptr;
      conv.bias = float_tensor(module, name + "bias");
      if (conv.bias.dim() != 1 || conv.bias.size(0) != conv.out) return nullptr;
    }
    if (conv.order > 0 && conv.out < conv.in) {
      // As the script: W [out, (K + 1) in] -> [W_0; W_1; ...], the bias joining u_0.
      const int64_t k1 = conv.order + 1;
      conv.stacked = conv.weight.view({conv.out, k1, in}).transpose(0, 1).reshape({k1 * conv.out, in}).contiguous();
      if (conv.bias.defined()) conv.extra = torch::cat({conv.bias, torch::zeros({conv.order * conv.out})});
    }
    if (e->precision_ == NetworkPrecision::bfloat16) {
      conv.weight16 = conv.weight.to(torch::kBFloat16).contiguous();
      if (conv.stacked.defined()) conv.stacked16 = conv.stacked.to(torch::kBFloat16).contiguous();
    }
    if (e->precision_ == NetworkPrecision::int8) {
      native_network_kernels::quantise_weights(conv.weight, conv.weight8, conv.weight8_scale);
      if (conv.stacked.defined())
        native_network_kernels::quantise_weights(conv.stacked, conv.stacked8, conv.stacked8_scale);
    }
    in = conv.out;
    e->convs_.push_back(std::move(conv));
  }
  if (e->convs_.empty()) return nullptr;
  e->hidden_weight_ = float_tensor(module, p + "encoder_hidden_weight");
  e->mean_weight_ = float_tensor(module, p + "mean_head_weight");
  if (module.hasattr(p + "encoder_hidden_bias")) e->hidden_bias_ = float_tensor(module, p + "encoder_hidden_bias");
  if (module.hasattr(p + "mean_head_bias")) e->mean_bias_ = float_tensor(module, p + "mean_head_bias");
  if (module.hasattr(p + "encoder_skip_weight")) {  // the linear input -> code path (models/mesh_vae.h)
    if (!module.attr(p + "encoder_skip_weight").isTensor()) return nullptr;
    e->skip_weight_ = float_tensor(module, p + "encoder_skip_weight");
    if (module.hasattr(p + "encoder_skip_bias")) e->skip_bias_ = float_tensor(module, p + "encoder_skip_bias");
    if (e->skip_weight_.dim() != 2 || e->skip_weight_.size(0) != e->mean_weight_.size(0) ||
        e->skip_weight_.size(1) != v * lo.size(1))
      return nullptr;
  }
  if (e->hidden_weight_.dim() != 2 || e->hidden_weight_.size(1) != v * in || e->mean_weight_.dim() != 2 ||
      e->mean_weight_.size(1) != e->hidden_weight_.size(0))
    return nullptr;
  if (e->precision_ == NetworkPrecision::bfloat16) e->hidden_weight16_ = e->hidden_weight_.to(torch::kBFloat16);
  if (e->precision_ == NetworkPrecision::int8)
    native_network_kernels::quantise_weights(e->hidden_weight_, e->hidden_weight8_, e->hidden_weight8_scale_);

  // The avatar decoder: leaky(z W1^T + b1) -> tanh(. W2^T + b2) as [B, Va, F] -> denormalised.
  const std::string a = "avatar_";
  bool decoder = module.find_method(a + "denormalise").has_value();
  for (const char* name : {"decoder_hidden_weight", "decoder_hidden_bias", "decoder_out_weight", "decoder_out_bias",
                           "normaliser_min", "normaliser_max"})
    decoder = decoder && module.hasattr(a + name) && module.attr(a + name).isTensor();
  if (decoder) {
    const torch::Tensor w1 = float_tensor(module, a + "decoder_hidden_weight"),
                        b1 = float_tensor(module, a + "decoder_hidden_bias"),
                        w2 = float_tensor(module, a + "decoder_out_weight"),
                        b2 = float_tensor(module, a + "decoder_out_bias"),
                        lo = float_tensor(module, a + "normaliser_min"),
                        hi = float_tensor(module, a + "normaliser_max");
    if (w1.dim() == 2 && b1.dim() == 1 && b1.size(0) == w1.size(0) && w2.dim() == 2 && w2.size(1) == w1.size(0) &&
        b2.dim() == 1 && b2.size(0) == w2.size(0) && lo.dim() == 2 && hi.sizes() == lo.sizes() &&
        lo.numel() == w2.size(0)) {
      e->decoder_hidden_weight_ = w1;
      e->decoder_hidden_bias_ = b1;
      e->decoder_out_weight_ = w2;
      e->decoder_out_bias_ = b2;
      e->avatar_lo_ = lo;
      e->avatar_scale_ = (hi - lo) / (2 * kNormalisedBound);  // as the script's denormalise
    }
  }
  return e;
}

// Terms first ([T0 h | T1 h | ... | TK h] W^T + b), block by block: T1..T(K-1) are whole signals
// (the next term gathers from them); TK is gathered straight into the block, next to copies of the
// others' rows, and the block's product is activated while it is in cache.
torch::Tensor NativeNetwork::conv_terms_first(const Conv& conv, const torch::Tensor& h, int64_t batch,
                                              bool last) const {
  using namespace native_network_kernels;
  const int64_t v = vertices_, in = conv.in, out = conv.out, k_max = conv.order, width = (k_max + 1) * in;
  const Operator op1{offsets_.data_ptr<int64_t>(), columns_.data_ptr<int64_t>(), values_.data_ptr<float>()};
  const Operator op2{op1.offsets, op1.columns, values2_.data_ptr<float>()};
  std::vector<torch::Tensor> t{h};
  for (int64_t k = 1; k < k_max; ++k) {
    t.push_back(torch::empty({v, batch * in}, torch::kFloat32));
    const Signal prev = k >= 2 ? whole(t[k - 2], batch, in) : Signal{};
    sparse_rows(k == 1 ? op1 : op2, whole(t[k - 1], batch, in), whole(t[k], batch, in), v, batch, in,
                [&](int64_t vertex, int64_t b, float* d) {
                  if (k < 2) return;
                  const float* before = prev.at(vertex, b);
                  for (int64_t c = 0; c < in; ++c) d[c] -= before[c];
                });
  }
  std::vector<Signal> terms;
  for (const torch::Tensor& term : t) terms.push_back(whole(term, batch, in));
  const Operator& op = k_max == 1 ? op1 : op2;

  torch::Tensor y = torch::empty({v * batch, out}, torch::kFloat32);
  float* y_data = y.data_ptr<float>();
  const float* weight = conv.weight.data_ptr<float>();
  const float* bias = conv.bias.defined() ? conv.bias.data_ptr<float>() : nullptr;
  const bool bf16 = precision_ == NetworkPrecision::bfloat16, int8 = precision_ == NetworkPrecision::int8;
  // Per GEMM row: the float32 terms, then (bfloat16) the same in half the room, or (int8) in a
  // quarter, its scale and the int32 sums.
  const int64_t room = bf16 ? width + (width + 1) / 2 : int8 ? width + (width + 3) / 4 + 1 + out : width;
  // The int8 scratch after the block's terms (of its largest size): int32 sums, scales, 8-bit rows.
  const int64_t block_rows = std::min(std::max<int64_t>(1, kBlockRows / batch), v) * batch;
  auto scale_of = [&](float* a) { return a + block_rows * (width + out); };
  auto q_of = [&](float* a) { return reinterpret_cast<uint8_t*>(scale_of(a) + block_rows); };
  // Where the CPU has AVX-512 and rows are wide enough to fill its registers, T_K (K >= 2) is summed
  // into each GEMM row directly.
  const bool fused = avx512_kernels_available() && k_max >= 2 && in >= 16;
  blocks(v, batch, room, [&](int64_t v0, int64_t v1, float* a) {
    std::vector<float> last_term(fused ? 0 : static_cast<size_t>(batch * in));  // the gathered T_K of one vertex
    const Signal gathered{last_term.data(), 0, in, 0};                          // one vertex: row stride 0
    for (int64_t vertex = v0; vertex < v1; ++vertex) {
      if (!fused) gather(op, terms[k_max - 1], gathered, vertex, batch, in);  // T_K h of this vertex, [B, in]
      for (int64_t b = 0; b < batch; ++b) {
        float* row = a + ((vertex - v0) * batch + b) * width;
        for (int64_t k = 0; k < k_max; ++k) std::copy_n(terms[k].at(vertex, b), in, row + k * in);
        float* into = row + k_max * in;
        if (fused) {  // T_K straight into the row: the sums, minus T_(K-2), in registers
          const int64_t first = op.offsets[vertex];
          const Signal& source = terms[k_max - 1];
          weighted_rows_avx512(op.columns + first, op.values + first, op.offsets[vertex + 1] - first,
                               source.data + b * source.sample, source.row, into, in,
                               RowStep{nullptr, terms[k_max - 2].at(vertex, b), false, 0.0f});
        } else if (k_max >= 2) {
          const float* d = last_term.data() + b * in;
          const float* before = terms[k_max - 2].at(vertex, b);
          for (int64_t c = 0; c < in; ++c) into[c] = d[c] - before[c];
        } else {
          std::copy_n(last_term.data() + b * in, in, into);
        }
        if (int8) {  // while the row is in L1
          const int64_t r = (vertex - v0) * batch + b;
          quantise_rows(row, 1, width, q_of(a) + r * width, scale_of(a) + r);
        }
      }
    }
    const int64_t rows = (v1 - v0) * batch;
    float* y_block = y_data + v0 * batch * out;
    if (bf16) {
      auto* a16 = reinterpret_cast<uint16_t*>(a + rows * width);
      to_bf16(a, rows * width, a16);
      product_bf16(a16, rows, width, bf16_data(conv.weight16), out, y_block);
    } else if (int8) {
      product_int8(q_of(a), scale_of(a), rows, width, conv.weight8.data_ptr<int8_t>(),
                   conv.weight8_scale.data_ptr<float>(), out, bias, last ? Activation::tanh : Activation::leaky,
                   reinterpret_cast<int32_t*>(a + block_rows * width), y_block);
      return;
    } else {
      product(a, rows, width, weight, out, y_block);
    }
    finish_product(y_block, rows, out, bias, last);
  });
  return y.view({v, batch * out});
}

// Row v of one step of Clenshaw's recurrence: dst(v, b, :) = (L~ src)(v, b, :) + add(v, b, :) -
// sub(v, b, :) (sub where sub.data), then LeakyReLU (tanh when `last`) where `activate`.
inline void recurrence_row(const Operator& op, const Signal& src, const Signal& add, const Signal& sub, bool activate,
                           bool last, const Signal& dst, int64_t v, int64_t batch, int64_t channels) {
  using namespace native_network_kernels;
  const float slope = static_cast<float>(kNativeNetworkSlope);
  if (avx512_kernels_available() && !(activate && last)) {
    const int64_t first = op.offsets[v], count = op.offsets[v + 1] - first;
    for (int64_t b = 0; b < batch; ++b)
      weighted_rows_avx512(op.columns + first, op.values + first, count, src.data + b * src.sample, src.row,
                           dst.at(v, b), channels,
                           RowStep{add.at(v, b), sub.data ? sub.at(v, b) : nullptr, activate, slope});
    return;
  }
  gather(op, src, dst, v, batch, channels);
  for (int64_t b = 0; b < batch; ++b) {
    float* d = dst.at(v, b);
    const float* plus = add.at(v, b);
    for (int64_t c = 0; c < channels; ++c) d[c] += plus[c];
    if (sub.data) {
      const float* minus = sub.at(v, b);
      for (int64_t c = 0; c < channels; ++c) d[c] -= minus[c];
    }
    if (activate)
      for (int64_t c = 0; c < channels; ++c) d[c] = last ? std::tanh(d[c]) : leaky(d[c], slope);
  }
}

// Weights first (a narrowing conv): Clenshaw's recurrence on the narrower signal, b_K = u_K,
// b_k = u_k + 2 L~ b_(k+1) - b_(k+2), y = u_0 + L~ b_1 - b_2, activated as it is written, where
// u_k = h W_k^T (+ b on u_0). Each step computes u_k block by block in the products' precision and
// adds it to the block's sparse sums while it is in L2, so u is never stored whole: at the paper's
// size it was [V B, (K + 1) out], 159 MB at batch 8, written once and read again. h is put in the
// products' precision once (8 bits per row with its scale, or bfloat16) and read by every step.
torch::Tensor NativeNetwork::conv_weights_first(const Conv& conv, const torch::Tensor& h, int64_t batch,
                                                bool last) const {
  using namespace native_network_kernels;
  const int64_t v = vertices_, in = conv.in, out = conv.out, k_max = conv.order, rows_all = v * batch;
  const Operator op1{offsets_.data_ptr<int64_t>(), columns_.data_ptr<int64_t>(), values_.data_ptr<float>()};
  const Operator op2{op1.offsets, op1.columns, values2_.data_ptr<float>()};
  const bool bf16 = precision_ == NetworkPrecision::bfloat16, int8 = precision_ == NetworkPrecision::int8;
  const float* h_data = h.data_ptr<float>();
  torch::Tensor low, low_scale;  // h in 8 bits and its row scales, or in bfloat16
  if (int8 || bf16) {
    low = torch::empty({rows_all, in}, int8 ? torch::kUInt8 : torch::kBFloat16);
    if (int8) low_scale = torch::empty({rows_all}, torch::kFloat32);
    at::parallel_for(0, rows_all, kBlockRows, [&](int64_t r0, int64_t r1) {
      if (int8)
        quantise_rows(h_data + r0 * in, r1 - r0, in, low.data_ptr<uint8_t>() + r0 * in,
                      low_scale.data_ptr<float>() + r0);
      else
        to_bf16(h_data + r0 * in, (r1 - r0) * in, reinterpret_cast<uint16_t*>(low.data_ptr()) + r0 * in);
    });
  }
  const float* u_bias = conv.extra.defined() ? conv.extra.data_ptr<float>() : nullptr;  // u_0's; zeros after
  std::vector<torch::Tensor> b_of(k_max + 1);
  for (int64_t k = k_max; k >= 0; --k) {
    b_of[k] = torch::empty({v, batch * out}, torch::kFloat32);
    const Signal dst = whole(b_of[k], batch, out);
    const Signal src = k < k_max ? whole(b_of[k + 1], batch, out) : Signal{};
    const Signal before = k + 2 <= k_max ? whole(b_of[k + 2], batch, out) : Signal{};
    const float* bias = k == 0 ? u_bias : nullptr;
    // Per GEMM row: u_k's out floats, then (8 bits) its out int32 sums.
    blocks(v, batch, int8 ? 2 * out : out, [&](int64_t v0, int64_t v1, float* scratch) {
      const int64_t rows = (v1 - v0) * batch, r0 = v0 * batch;
      float* u = k == k_max ? dst.at(v0, 0) : scratch;  // b_K = u_K, written in place
      if (int8) {
        product_int8(low.data_ptr<uint8_t>() + r0 * in, low_scale.data_ptr<float>() + r0, rows, in,
                     conv.stacked8.data_ptr<int8_t>() + k * out * in, conv.stacked8_scale.data_ptr<float>() + k * out,
                     out, bias, Activation::none, reinterpret_cast<int32_t*>(scratch + rows * out), u);
      } else {
        if (bf16)
          product_bf16(bf16_data(low) + r0 * in, rows, in, bf16_data(conv.stacked16) + k * out * in, out, u);
        else
          product(h_data + r0 * in, rows, in, conv.stacked.data_ptr<float>() + k * out * in, out, u);
        if (bias)
          for (int64_t r = 0; r < rows; ++r)
            for (int64_t c = 0; c < out; ++c) u[r * out + c] += bias[c];
      }
      if (k == k_max) return;
      const Signal uk{scratch, batch * out, out, v0};
      for (int64_t vertex = v0; vertex < v1; ++vertex)
        recurrence_row(k > 0 ? op2 : op1, src, uk, before, k == 0, last, dst, vertex, batch, out);
    });
  }
  return b_of[0];
}

torch::Tensor NativeNetwork::encode_human(const torch::Tensor& raw) const {
  TORCH_CHECK(raw.dim() == 3 && raw.size(1) == vertices_ && raw.size(2) == 9, "encode_human: expected x of shape [B, ",
              vertices_, ", 9] (raw human DR features), got ", raw.sizes());
  torch::jit::Module module = module_;
  const torch::Tensor x = module.run_method("human_normalise", raw).toTensor().to(torch::kFloat32);
  const int64_t batch = x.size(0), v = vertices_;
  torch::Tensor h = x.transpose(0, 1).contiguous().view({v, batch * x.size(2)});  // [V, B, F]
  for (size_t i = 0; i < convs_.size(); ++i) {
    const Conv& conv = convs_[i];
    const bool last = i + 1 == convs_.size();
    if (conv.order == 0) {
      h = torch::linear(h.view({v * batch, conv.in}), conv.weight, conv.bias);
      h = last ? h.tanh_() : at::leaky_relu_(h, kNativeNetworkSlope);
      h = h.view({v, batch * conv.out});
    } else if (conv.out >= conv.in) {
      h = conv_terms_first(conv, h, batch, last);
    } else {
      h = conv_weights_first(conv, h, batch, last);
    }
  }
  const int64_t c = convs_.back().out;
  const torch::Tensor flat = h.view({v, batch, c}).transpose(0, 1).contiguous();  // [B, V * C]
  torch::Tensor mean = torch::linear(hidden_layer(flat), mean_weight_, mean_bias_);
  if (skip_weight_.defined()) mean += torch::linear(x.reshape({batch, v * x.size(2)}), skip_weight_, skip_bias_);
  return mean;
}

// The encoder's dense hidden layer, [B, V * C] -> leaky([B, hidden]): at batch 1 a pass over its
// weights (13 MB at the paper's size), so in the network's precision (a quarter of the bytes in
// 8 bits, half in bfloat16) and, in float32 and bfloat16, split by outputs over LibTorch's
// threads (each core reads its share of the weights).
torch::Tensor NativeNetwork::hidden_layer(const torch::Tensor& flat) const {
  using namespace native_network_kernels;
  const int64_t batch = flat.size(0), k = flat.size(1), n = hidden_weight_.size(0);
  const float* bias = hidden_bias_.defined() ? hidden_bias_.data_ptr<float>() : nullptr;
  torch::Tensor hidden = torch::empty({batch, n}, torch::kFloat32);
  float* out = hidden.data_ptr<float>();
  if (precision_ == NetworkPrecision::int8) {
    std::vector<uint8_t> q(static_cast<size_t>(batch * k));
    std::vector<float> scale(static_cast<size_t>(batch));
    std::vector<int32_t> acc(static_cast<size_t>(batch * n));
    quantise_rows(flat.data_ptr<float>(), batch, k, q.data(), scale.data());
    product_int8(q.data(), scale.data(), batch, k, hidden_weight8_.data_ptr<int8_t>(),
                 hidden_weight8_scale_.data_ptr<float>(), n, bias, Activation::leaky, acc.data(), out);
    return hidden;
  }
  std::vector<uint16_t> a16;
  if (precision_ == NetworkPrecision::bfloat16) {
    a16.resize(static_cast<size_t>(batch * k));
    to_bf16(flat.data_ptr<float>(), batch * k, a16.data());
  }
  const int64_t grain = dnnl_sgemm() ? 64 : n;
  at::parallel_for(0, n, grain, [&](int64_t j0, int64_t j1) {
    if (!a16.empty()) {
      product_bf16(a16.data(), batch, k, bf16_data(hidden_weight16_) + j0 * k, j1 - j0, out + j0, n);
    } else {
      product(flat.data_ptr<float>(), batch, k, hidden_weight_.data_ptr<float>() + j0 * k, j1 - j0, out + j0, n);
    }
  });
  if (bias) hidden += hidden_bias_;
  return at::leaky_relu_(hidden, kNativeNetworkSlope);
}

torch::Tensor NativeNetwork::decode_avatar(const torch::Tensor& code) const {
  TORCH_CHECK(decodes(), "NativeNetwork::decode_avatar: this bundle's decoder does not run natively");
  TORCH_CHECK(code.dim() == 2 && code.size(1) == decoder_hidden_weight_.size(1),
              "avatar_decode_normalised: expected z of shape [B, ", decoder_hidden_weight_.size(1),
              "] (latent codes), got ", code.sizes());
  const torch::Tensor hidden =
      torch::leaky_relu(torch::linear(code.to(torch::kFloat32), decoder_hidden_weight_, decoder_hidden_bias_),
                        kNativeNetworkSlope)
          .contiguous();
  const int64_t batch = code.size(0), width = decoder_out_weight_.size(0);
  torch::Tensor y = torch::empty({batch, width}, torch::kFloat32);
  native_network_kernels::product(hidden.data_ptr<float>(), batch, hidden.size(1),
                                  decoder_out_weight_.data_ptr<float>(), width, y.data_ptr<float>());
  y += decoder_out_bias_;
  y.tanh_();
  // As the script's denormalise: (y + 0.9) * ((hi - lo) / 1.8) + lo.
  return ((y.view({batch, avatar_lo_.size(0), avatar_lo_.size(1)}) + kNormalisedBound) * avatar_scale_) + avatar_lo_;
}

}  // namespace retarget
