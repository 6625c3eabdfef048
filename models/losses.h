// Training losses of the mesh VAEs and of the translation network F.
#pragma once

#include <torch/torch.h>

#include <string>

namespace retarget {

// How a VAE's reconstruction is scored in training (`loss.reconstruction`). L1 (the method
// notes' choice) is minimised by the per-element median: on an avatar whose regions each move in
// a minority of the samples, the median of every channel is the neutral, and a VAE can settle
// there (the quick synthetic fox did). The squared error is minimised by the mean, which keeps
// the minority motions in the gradient.
enum class ReconstructionLoss { l1, squared };

// "l1" / "squared"; the parser throws retarget::Error naming `key_path` for anything else.
const char* to_string(ReconstructionLoss loss);
ReconstructionLoss parse_reconstruction_loss(const std::string& name, const std::string& key_path);

// Scalar (0-dim) float32 tensors, all differentiable.
struct VaeLoss {
  torch::Tensor total;           // reconstruction + kl_weight * kl
  torch::Tensor reconstruction;  // L1 or squared error (ReconstructionLoss), mean over all elements
  torch::Tensor kl;              // KL(N(mean, exp(logvar)) || N(0, I)), summed over latent dims,
                                 // averaged over the batch
};

// recon, target: [B, V, F] (any equal shapes with batch first); mean, logvar: [B, latent].
// kl_weight >= 0 (method notes: 1e-5 for the human VAE). Throws retarget::Error naming
// "vae_loss.kl_weight" for a negative or NaN weight.
//   KL per sample = -1/2 * sum_j (1 + logvar_j - mean_j^2 - exp(logvar_j))
VaeLoss vae_loss(const torch::Tensor& recon, const torch::Tensor& target, const torch::Tensor& mean,
                 const torch::Tensor& logvar, double kl_weight,
                 ReconstructionLoss reconstruction = ReconstructionLoss::l1);

// Losses of the translation network F (paper, eqs. 4-7; method notes "Networks"). Every distance
// is the SQUARED Euclidean distance in the avatar latent space: eqs. 4 and 5 square the norm
// explicitly, and eq. 7's D(a, p) = ||F(x_a) - y_p||^2 is the same squared norm (the "2" of the
// extracted text is the superscript of eqs. 4-5, and squared distances are what the triplet loss
// of the paper's reference [45], FaceNet, uses). So the margin 0.2 is in squared code units.
// All return 0-dim float32 tensors, differentiable in `translated`; codes are encoder means.

// L_P = 1/K sum_k ||F(x_k) - y0_k||^2.  translated = F(x): [K, L]; y0: [K, L]; K >= 1.
torch::Tensor paired_loss(const torch::Tensor& translated, const torch::Tensor& y0);

// L_G = 1/(K P) sum_k sum_p ||F(x_k) - y_pk||^2.  translated: [K, L]; group_codes: [K, P, L].
torch::Tensor group_loss(const torch::Tensor& translated, const torch::Tensor& group_codes);

// L_T = 1/T sum_t max(0, margin + D(a_t, p_t) - D(a_t, n_t)), D(a, y) = s_t ||F(x_a) - y||^2.
// anchor = F(x_a): [T, L]; positive, negative: [T, L]; margin >= 0 (paper: 0.2). T = 0 gives 0.
// scale: s_t, [T] float32 > 0, the unit each triplet's distances are measured in (the trainer's
// `loss.triplet_scale: group` passes 1 / the spread of the triplet's group); undefined: s_t = 1,
// the paper's absolute squared code distances.
// Throws retarget::Error naming "triplet_loss.margin" for a negative or NaN margin.
torch::Tensor triplet_loss(const torch::Tensor& anchor, const torch::Tensor& positive, const torch::Tensor& negative,
                           double margin = 0.2, const torch::Tensor& scale = {});

// Fraction of triplets with D(a, p) < D(a, n) (ties count as wrong), in [0, 1]; NaN for T = 0.
// Shapes as triplet_loss. Not differentiable (a plain double).
double triplet_accuracy(const torch::Tensor& anchor, const torch::Tensor& positive, const torch::Tensor& negative);

}  // namespace retarget
