// Chebyshev graph convolution (Defferrard et al. 2016) on a fixed mesh graph:
//   T0 x = x, T1 x = L~ x, Tk x = 2 L~ T(k-1) x - T(k-2) x,
//   y = Linear([T0 x | T1 x | ... | T_order x])   (weights shared over vertices)
// The activation is applied by the caller (MeshVae), as the frontend's Linear does.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <string>

namespace retarget {

struct ChebyshevConvOptions {
  ChebyshevConvOptions(int64_t in, int64_t out) : in_(in), out_(out) {}
  void validate(const std::string& key_path = "chebyshev_conv") const;  // throws retarget::Error

  TORCH_ARG(int64_t, in);         // input channels per vertex, > 0
  TORCH_ARG(int64_t, out);        // output channels per vertex, > 0
  TORCH_ARG(int64_t, order) = 2;  // highest Chebyshev term: T0..T_order (order + 1 terms), >= 0
  TORCH_ARG(bool, bias) = true;
};

class ChebyshevConvImpl : public torch::nn::Cloneable<ChebyshevConvImpl> {
 public:
  // laplacian: [V, V] rescaled Laplacian L~ (graph_operator()), sparse COO or dense, float32.
  // Registered as the buffer "laplacian" (moves with .to(), is no parameter).
  ChebyshevConvImpl(torch::Tensor laplacian, const ChebyshevConvOptions& options);

  void reset() override;
  void pretty_print(std::ostream& stream) const override;

  // x: [B, V, in] float32 -> [B, V, out]. The concatenated features are ordered term-major:
  // channel k * in + c holds (T_k x)_c, matching linear->weight [out, in * (order + 1)].
  // With a sparse operator on CPU (float32/64) the terms come from a compressed-row kernel in the
  // [B, V, C] layout, and when out < in the Linear is applied first (sum_k T_k (x W_k^T)); the
  // map is the same up to rounding. That path has no double backward (create_graph).
  torch::Tensor forward(const torch::Tensor& x);

  ChebyshevConvOptions options;
  torch::Tensor laplacian;
  torch::nn::Linear linear{nullptr};
};

TORCH_MODULE(ChebyshevConv);

}  // namespace retarget
