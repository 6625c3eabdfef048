#include "models/losses.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "core/config.h"
#include "core/error.h"

namespace retarget {

const char* to_string(ReconstructionLoss loss) { return loss == ReconstructionLoss::l1 ? "l1" : "squared"; }

ReconstructionLoss parse_reconstruction_loss(const std::string& name, const std::string& key_path) {
  if (name == "l1") return ReconstructionLoss::l1;
  if (name == "squared") return ReconstructionLoss::squared;
  throw Error(key_path, fmt::format("expected 'l1' or 'squared', got '{}'", name));
}

VaeLoss vae_loss(const torch::Tensor& recon, const torch::Tensor& target, const torch::Tensor& mean,
                 const torch::Tensor& logvar, double kl_weight, ReconstructionLoss reconstruction) {
  require_non_negative(kl_weight, "vae_loss.kl_weight");
  TORCH_CHECK(recon.sizes() == target.sizes(), "vae_loss: reconstruction ", recon.sizes(), " and target ",
              target.sizes(), " differ in shape");
  TORCH_CHECK(mean.dim() == 2 && mean.sizes() == logvar.sizes(), "vae_loss: expected mean and logvar [B, latent], got ",
              mean.sizes(), " and ", logvar.sizes());
  VaeLoss loss;
  loss.reconstruction =
      reconstruction == ReconstructionLoss::l1 ? torch::l1_loss(recon, target) : torch::mse_loss(recon, target);
  loss.kl = (-0.5 * (1.0 + logvar - mean.pow(2) - logvar.exp()).sum(1)).mean();
  loss.total = loss.reconstruction + kl_weight * loss.kl;
  return loss;
}

namespace {

// ||a - b||^2 per row: a, b [T, L] -> [T].
torch::Tensor squared_distance(const torch::Tensor& a, const torch::Tensor& b) { return (a - b).pow(2).sum(-1); }

void check_triplet_shapes(const char* what, const torch::Tensor& anchor, const torch::Tensor& positive,
                          const torch::Tensor& negative) {
  TORCH_CHECK(anchor.dim() == 2 && positive.sizes() == anchor.sizes() && negative.sizes() == anchor.sizes(), what,
              ": expected anchor, positive and negative [T, L], got ", anchor.sizes(), ", ", positive.sizes(), " and ",
              negative.sizes());
}

}  // namespace

torch::Tensor paired_loss(const torch::Tensor& translated, const torch::Tensor& y0) {
  TORCH_CHECK(translated.dim() == 2 && translated.size(0) > 0 && y0.sizes() == translated.sizes(),
              "paired_loss: expected F(x) and y0 [K, L] with K >= 1, got ", translated.sizes(), " and ", y0.sizes());
  return squared_distance(translated, y0).mean();
}

torch::Tensor group_loss(const torch::Tensor& translated, const torch::Tensor& group_codes) {
  TORCH_CHECK(translated.dim() == 2 && translated.size(0) > 0 && group_codes.dim() == 3 &&
                  group_codes.size(0) == translated.size(0) && group_codes.size(1) > 0 &&
                  group_codes.size(2) == translated.size(1),
              "group_loss: expected F(x) [K, L] and group codes [K, P, L] with K, P >= 1, got ", translated.sizes(),
              " and ", group_codes.sizes());
  // Mean over k and p of the squared distances = 1/(KP) sum_k sum_p.
  return squared_distance(translated.unsqueeze(1), group_codes).mean();
}

torch::Tensor triplet_loss(const torch::Tensor& anchor, const torch::Tensor& positive, const torch::Tensor& negative,
                           double margin, const torch::Tensor& scale) {
  require_non_negative(margin, "triplet_loss.margin");
  check_triplet_shapes("triplet_loss", anchor, positive, negative);
  TORCH_CHECK(!scale.defined() || (scale.dim() == 1 && scale.size(0) == anchor.size(0)),
              "triplet_loss: expected scale [T] with T = ", anchor.size(0), ", got ", scale.sizes());
  if (anchor.size(0) == 0) return (anchor.sum() * 0).to(torch::kFloat32);
  torch::Tensor difference = squared_distance(anchor, positive) - squared_distance(anchor, negative);
  if (scale.defined()) difference = difference * scale;
  return torch::relu(margin + difference).mean();
}

double triplet_accuracy(const torch::Tensor& anchor, const torch::Tensor& positive, const torch::Tensor& negative) {
  check_triplet_shapes("triplet_accuracy", anchor, positive, negative);
  if (anchor.size(0) == 0) return std::numeric_limits<double>::quiet_NaN();
  torch::NoGradGuard no_grad;
  return (squared_distance(anchor, positive) < squared_distance(anchor, negative))
      .to(torch::kFloat64)
      .mean()
      .item<double>();
}

}  // namespace retarget
