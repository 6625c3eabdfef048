// A VAE encoder started at the principal codes of train/principal_decoder.h, through its linear
// skip (MeshVaeOptions::encoder_skip), so that the untrained VAE is already the rank-k principal
// autoencoder of its training data instead of a random map.
//
// The paper's encoder narrows every vertex to one channel before its dense layer, and started at
// random it has to learn the whole map from features to code. Measured on held-out rig samples
// (normalised feature L1 as a fraction of the neutral answer's, tools in docs/experiments/2026-11-26-vae-starts.md):
// the linear rank-latent principal autoencoder reaches x0.13 on the synthetic fox (the quick VAE after training: x0.37)
// and x0.15 on the ICT head as a 53-controller rig (the good VAE after 40 epochs: x0.28).
//
//   encoder_skip.weight[:k] = A^T X_c,  A = (X_c X_c^T + lambda I)^-1 C,   (ridge regression, dual form)
//   encoder_skip.bias[:k]   = -encoder_skip.weight[:k] mean(X)
//   encoder_skip rows >= k, mean_head: 0;  logvar_head: weight 0, bias kStartLogVariance
//
// X: the input rows [N, V * F] (a person's expression for the human VAE, the rig sample for the
// avatar's), X_c centred; C [N, k]: the codes of their targets' principal coefficients
// (PrincipalDecoderStart::codes); lambda = kRidge * trace(X_c X_c^T) / N. The graph-conv path
// starts at 0 in the mean (mean_head 0) and trains from there; the posterior starts narrow
// (standard deviation exp(kStartLogVariance / 2) ~ 0.03 of a code's spread) so that sampling does
// not swamp the codes before training has begun.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <vector>

#include "models/mesh_vae.h"

namespace retarget {

constexpr double kRidge = 1e-2;             // lambda as a fraction of the rows' mean square norm
constexpr double kStartLogVariance = -7.0;  // logvar_head's starting bias

struct PrincipalEncoderStart {
  int64_t components = 0;  // code coordinates fitted, k
  double fit = 0;          // the fitted codes' residual on the rows, mean square per coordinate (codes have 1)
};

// inputs: [M, V, F] float32 normalised encoder inputs; rows: [N] rows of inputs, one per row of
// codes ([N, k] float32, k <= latent, N >= 2). The VAE must have an encoder skip. Works in
// column blocks of the inputs, never holding a [N, V * F] copy.
// Throws retarget::Error on a VAE without a skip, mismatched shapes or rows out of range.
PrincipalEncoderStart start_encoder_at_principal_codes(MeshVaeImpl& vae, const torch::Tensor& inputs,
                                                       const std::vector<int64_t>& rows, const torch::Tensor& codes);

}  // namespace retarget
