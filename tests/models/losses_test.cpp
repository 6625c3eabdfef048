#include "models/losses.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "core/error.h"

namespace retarget {
namespace {

TEST_CASE("vae_loss: KL of the prior is 0", "[losses]") {
  const torch::Tensor x = torch::ones({3, 4, 9});
  const VaeLoss loss = vae_loss(x, x, torch::zeros({3, 25}), torch::zeros({3, 25}), 1.0);
  CHECK(loss.kl.item<double>() == Approx(0.0).margin(1e-7));
  CHECK(loss.reconstruction.item<double>() == Approx(0.0).margin(1e-7));
  CHECK(loss.total.item<double>() == Approx(0.0).margin(1e-7));
  CHECK(loss.total.dim() == 0);
}

TEST_CASE("vae_loss matches a hand-worked value", "[losses]") {
  // Sample 0: mean (1, 0), logvar (0, ln 2): KL = 1/2 * (1 + 0 - 0) + 1/2 * (0 + 2 - 1 - ln 2)
  //   = 0.5 + 0.5 - 0.5 ln 2. Sample 1 is the prior (KL 0). Batch mean: (1 - 0.5 ln 2) / 2.
  const torch::Tensor mean = torch::tensor({1.0f, 0.0f, 0.0f, 0.0f}).view({2, 2});
  const torch::Tensor logvar = torch::tensor({0.0f, float(std::log(2.0)), 0.0f, 0.0f}).view({2, 2});
  // L1: |1| + |-2| + |0| + |0.5| over 4 elements = 0.875.
  const torch::Tensor recon = torch::tensor({1.0f, -2.0f, 0.0f, 0.5f}).view({2, 1, 2});
  const torch::Tensor target = torch::zeros({2, 1, 2});
  const VaeLoss loss = vae_loss(recon, target, mean, logvar, 0.1);
  const double kl = (1.0 - 0.5 * std::log(2.0)) / 2.0;
  CHECK(loss.kl.item<double>() == Approx(kl).epsilon(1e-6));
  CHECK(loss.reconstruction.item<double>() == Approx(0.875).epsilon(1e-6));
  CHECK(loss.total.item<double>() == Approx(0.875 + 0.1 * kl).epsilon(1e-6));
}

TEST_CASE("vae_loss rejects a negative KL weight with a message", "[losses]") {
  const torch::Tensor x = torch::zeros({1, 2, 9});
  const torch::Tensor m = torch::zeros({1, 3});
  CHECK_THROWS_AS(vae_loss(x, x, m, m, -1.0), Error);
  CHECK_THROWS_WITH(vae_loss(x, x, m, m, -1.0), "vae_loss.kl_weight: expected a number >= 0, got -1");
}

}  // namespace
}  // namespace retarget
