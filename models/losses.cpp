#include "models/losses.h"

#include "core/config.h"

namespace retarget {

VaeLoss vae_loss(const torch::Tensor& recon, const torch::Tensor& target, const torch::Tensor& mean,
                 const torch::Tensor& logvar, double kl_weight) {
  require_non_negative(kl_weight, "vae_loss.kl_weight");
  TORCH_CHECK(recon.sizes() == target.sizes(), "vae_loss: reconstruction ", recon.sizes(), " and target ",
              target.sizes(), " differ in shape");
  TORCH_CHECK(mean.dim() == 2 && mean.sizes() == logvar.sizes(), "vae_loss: expected mean and logvar [B, latent], got ",
              mean.sizes(), " and ", logvar.sizes());
  VaeLoss loss;
  loss.reconstruction = torch::l1_loss(recon, target);
  loss.kl = (-0.5 * (1.0 + logvar - mean.pow(2) - logvar.exp()).sum(1)).mean();
  loss.total = loss.reconstruction + kl_weight * loss.kl;
  return loss;
}

}  // namespace retarget
