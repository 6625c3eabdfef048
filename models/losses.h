// Training losses of the mesh VAEs.
#pragma once

#include <torch/torch.h>

namespace retarget {

// Scalar (0-dim) float32 tensors, all differentiable.
struct VaeLoss {
  torch::Tensor total;           // reconstruction + kl_weight * kl
  torch::Tensor reconstruction;  // L1, mean over all elements
  torch::Tensor kl;              // KL(N(mean, exp(logvar)) || N(0, I)), summed over latent dims,
                                 // averaged over the batch
};

// recon, target: [B, V, F] (any equal shapes with batch first); mean, logvar: [B, latent].
// kl_weight >= 0 (method notes: 1e-5 for the human VAE). Throws retarget::Error naming
// "vae_loss.kl_weight" for a negative or NaN weight.
//   KL per sample = -1/2 * sum_j (1 + logvar_j - mean_j^2 - exp(logvar_j))
VaeLoss vae_loss(const torch::Tensor& recon, const torch::Tensor& target, const torch::Tensor& mean,
                 const torch::Tensor& logvar, double kl_weight);

}  // namespace retarget
