// The bundle's network natively, the scripted module's maths op for op: the human encoder's graph convolutions run
// natively, cache-blocked, instead of through the bundle's TorchScript (issue 16): the script's sparse products,
// concatenations, subtractions and activations each stream a [V, B, C] signal (tens of MB at batch 8) through memory,
// and together they cost more than the dense products. Here each graph conv is one pass over blocks of vertices: the
// block's Chebyshev terms are gathered (the compressed rows of the bundle's own operator; with AVX-512, even and odd
// entries in two chains of sums, infer/network_kernels_avx512.h) into a buffer that stays in cache, multiplied by the
// conv's weights (oneDNN's GEMM) and activated in place. The same sums as the script in float32; only the rounding of
// the reordered and fused steps differs (tests compare both within 1e-5).
//
// It reads the bundle's own tensors (human_laplacian_*, human_convs_<i>_linear_*,
// human_encoder_hidden_*, human_mean_head_*, human_encoder_skip_* where present) and runs the module's human_normalise
// for the input; a bundle that lacks any of them (or whose shapes do not chain) gets no native encoder and keeps its
// scripted one.
#pragma once

#include <torch/script.h>
#include <torch/torch.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "infer/network_precision.h"

namespace retarget {

// The negative slope of the encoder's LeakyReLUs: models/mesh_vae.h's kMeshVaeSlope, which the
// runtime does not include (tests/infer checks that they agree).
constexpr double kNativeNetworkSlope = 0.1;

// Whether this CPU and LibTorch run the graph convs' products in `precision`
// (infer/network_precision.h); a precision they lack falls back to float32
// (NativeNetwork::precision() says which ran).
bool network_precision_available(NetworkPrecision precision);

// The routine the graph convs' products call in `precision` here, for benchmarks and logs:
// "oneDNN dnnl_sgemm" (or "LibTorch mm" without oneDNN), "oneDNN dnnl_gemm_bf16bf16f32 on AVX512_CORE_AMX",
// "oneDNN dnnl_gemm_u8s8s32 on AVX512_CORE_BF16" (the instruction set oneDNN runs: infer/onednn_isa.h);
// with " (not on this CPU)" instead where the precision is not available.
std::string network_products_kernel(NetworkPrecision precision);

// What runs the native network's other loops here (the sparse rows, 8-bit quantisation and the
// 8-bit products' epilogue): "AVX-512 intrinsics" (infer/network_kernels_avx512.h) or, on CPUs
// without AVX-512, "compiler-vectorised loops (AVX2 or baseline)".
std::string network_loops_kernel();

class NativeNetwork {
 public:
  // The native encoder of a bundle module's human side, or nullptr when the module does not have
  // the expected tensors (then use the module's own encode_human).
  // precision: of the graph convs' dense products (above); tests/infer bounds each one's error
  // against float32's.
  static std::unique_ptr<NativeNetwork> of_bundle(const torch::jit::Module& module,
                                                  NetworkPrecision precision = NetworkPrecision::float32);

  // [B, V, 9] raw human DR features -> [B, latent] codes (encoder means): the module's
  // encode_human. Throws (TORCH_CHECK) for another shape.
  torch::Tensor encode_human(const torch::Tensor& raw) const;

  // Whether decode_avatar runs natively (the module has the avatar decoder's tensors).
  bool decodes() const { return decoder_out_weight_.defined(); }
  // [B, latent] avatar codes -> [B, Va, 9] raw avatar DR features: the module's decode_avatar, its
  // wide last Linear through oneDNN's sgemm (LibTorch's addmm repacks its 17874 x 300 weights on
  // every call: 3 ms a frame at batch 1). Only if decodes().
  torch::Tensor decode_avatar(const torch::Tensor& code) const;

  int64_t vertices() const { return vertices_; }
  NetworkPrecision precision() const { return precision_; }  // what the products run in

 private:
  struct Conv {
    int64_t in = 0, out = 0, order = 0;
    torch::Tensor weight, bias;                   // the Linear's, [out, (K + 1) in] and [out] (bias may be undefined)
    torch::Tensor stacked, extra;                 // narrowing convs: [W_0; W_1; ...] [(K + 1) out, in], bias and zeros
    torch::Tensor weight16, stacked16;            // bfloat16 copies (bfloat16 products only)
    torch::Tensor weight8, stacked8;              // int8 copies per output row (int8 products only) ...
    torch::Tensor weight8_scale, stacked8_scale;  // ... and their scales, [out] and [(K + 1) out]
  };

  NativeNetwork() = default;
  torch::Tensor conv_terms_first(const Conv& conv, const torch::Tensor& h, int64_t batch, bool last) const;
  torch::Tensor conv_weights_first(const Conv& conv, const torch::Tensor& h, int64_t batch, bool last) const;
  // The encoder's dense hidden layer in the products' precision: [B, V * C] -> leaky([B, hidden]).
  torch::Tensor hidden_layer(const torch::Tensor& flat) const;

  torch::jit::Module module_;  // for human_normalise
  int64_t vertices_ = 0;
  NetworkPrecision precision_ = NetworkPrecision::float32;
  torch::Tensor offsets_;                     // [V + 1] int64: row v's entries are offsets_[v] .. offsets_[v + 1] - 1
  torch::Tensor columns_, values_, values2_;  // [nnz] int64, float32, float32 (2 L~)
  std::vector<Conv> convs_;
  torch::Tensor hidden_weight_, hidden_bias_, mean_weight_, mean_bias_;
  torch::Tensor hidden_weight16_, hidden_weight8_, hidden_weight8_scale_;  // in the products' precision
  torch::Tensor skip_weight_, skip_bias_;  // human_encoder_skip_*, where the bundle's VAE has one
  // The avatar decoder (undefined: none) and the avatar denormaliser's lo and (hi - lo) / 1.8.
  torch::Tensor decoder_hidden_weight_, decoder_hidden_bias_, decoder_out_weight_, decoder_out_bias_;
  torch::Tensor avatar_lo_, avatar_scale_;
};

}  // namespace retarget
