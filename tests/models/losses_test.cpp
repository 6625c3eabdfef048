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

TEST_CASE("vae_loss: the squared reconstruction error matches a hand-worked value", "[losses]") {
  // (1 + 4 + 0 + 0.25) / 4 = 1.3125; the prior's KL is 0.
  const torch::Tensor recon = torch::tensor({1.0f, -2.0f, 0.0f, 0.5f}).view({2, 1, 2});
  const torch::Tensor zeros = torch::zeros({2, 2});
  const VaeLoss loss = vae_loss(recon, torch::zeros({2, 1, 2}), zeros, zeros, 0.1, ReconstructionLoss::squared);
  CHECK(loss.reconstruction.item<double>() == Approx(1.3125).epsilon(1e-6));
  CHECK(loss.total.item<double>() == Approx(1.3125).epsilon(1e-6));
  // A channel that moves in one sample of four: L1's best constant is the median (0, the
  // neutral), the squared error's the mean (0.25). The gradient at 0 says which one pulls away.
  const torch::Tensor target = torch::tensor({0.0f, 0.0f, 0.0f, 1.0f}).view({4, 1, 1});
  const torch::Tensor constant = torch::full({4, 1, 1}, 0.1f).requires_grad_();
  const torch::Tensor m = torch::zeros({4, 1});
  vae_loss(constant, target, m, m, 0.0, ReconstructionLoss::l1).total.backward();
  CHECK(constant.grad().sum().item<double>() > 0);  // L1 pushes 0.1 back down to the neutral
  constant.grad().zero_();
  vae_loss(constant, target, m, m, 0.0, ReconstructionLoss::squared).total.backward();
  CHECK(constant.grad().sum().item<double>() < 0);  // the squared error pushes it up to the mean
}

TEST_CASE("reconstruction loss names read back and others are refused", "[losses]") {
  CHECK(parse_reconstruction_loss("l1", "loss.reconstruction") == ReconstructionLoss::l1);
  CHECK(parse_reconstruction_loss("squared", "loss.reconstruction") == ReconstructionLoss::squared);
  CHECK(std::string(to_string(ReconstructionLoss::squared)) == "squared");
  CHECK_THROWS_WITH(parse_reconstruction_loss("L2", "loss.reconstruction"),
                    "loss.reconstruction: expected 'l1' or 'squared', got 'L2'");
}

TEST_CASE("vae_loss rejects a negative KL weight with a message", "[losses]") {
  const torch::Tensor x = torch::zeros({1, 2, 9});
  const torch::Tensor m = torch::zeros({1, 3});
  CHECK_THROWS_AS(vae_loss(x, x, m, m, -1.0), Error);
  CHECK_THROWS_WITH(vae_loss(x, x, m, m, -1.0), "vae_loss.kl_weight: expected a number >= 0, got -1");
}

TEST_CASE("paired_loss matches a hand-worked value and gradient", "[losses]") {
  // ||(1, 2) - (0, 0)||^2 = 5, ||(0, 0) - (3, 4)||^2 = 25: mean over K = 2 is 15.
  const torch::Tensor f = torch::tensor({1.0f, 2.0f, 0.0f, 0.0f}).view({2, 2}).requires_grad_();
  const torch::Tensor y0 = torch::tensor({0.0f, 0.0f, 3.0f, 4.0f}).view({2, 2});
  const torch::Tensor loss = paired_loss(f, y0);
  CHECK(loss.dim() == 0);
  CHECK(loss.item<double>() == Approx(15.0));
  loss.backward();
  // d/dF = 2 (F - y0) / K = (1, 2), (-3, -4).
  CHECK(torch::allclose(f.grad(), torch::tensor({1.0f, 2.0f, -3.0f, -4.0f}).view({2, 2})));
}

TEST_CASE("group_loss matches a hand-worked value", "[losses]") {
  // k = 0: F = (0, 0), group (1, 0) and (0, 2): 1 + 4. k = 1: F = (1, 1), group (1, 1) and
  // (3, 1): 0 + 4. 1/(K P) = 1/4 of 9 = 2.25.
  const torch::Tensor f = torch::tensor({0.0f, 0.0f, 1.0f, 1.0f}).view({2, 2});
  const torch::Tensor group = torch::tensor({1.0f, 0.0f, 0.0f, 2.0f, 1.0f, 1.0f, 3.0f, 1.0f}).view({2, 2, 2});
  CHECK(group_loss(f, group).item<double>() == Approx(2.25));
  // A group of one code is the paired loss.
  CHECK(group_loss(f, group.slice(1, 0, 1)).item<double>() ==
        Approx(paired_loss(f, group.select(1, 0)).item<double>()));
}

TEST_CASE("triplet_loss and triplet_accuracy match hand-worked values", "[losses]") {
  // Squared distances, margin 0.2:
  //   t0: a (0, 0), p (1, 0), n (0, 2):   D(a,p) 1, D(a,n) 4     -> max(0, 0.2 + 1 - 4) = 0, right
  //   t1: a (0, 0), p (0, 1), n (0, 0.5): D(a,p) 1, D(a,n) 0.25  -> 0.2 + 1 - 0.25 = 0.95, wrong
  //   t2: a (1, 0), p (1, 0), n (0, 0):   D(a,p) 0, D(a,n) 1     -> 0, right
  //   t3: a (0, 0), p (0, 1), n (1, 0.3): D(a,p) 1, D(a,n) 1.09  -> 0.2 + 1 - 1.09 = 0.11, right
  //       (right, but inside the margin)
  // L_T = (0.95 + 0.11) / 4 = 0.265; accuracy 3/4.
  const torch::Tensor a = torch::tensor({0.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f}).view({4, 2});
  const torch::Tensor p = torch::tensor({1.0f, 0.0f, 0.0f, 1.0f, 1.0f, 0.0f, 0.0f, 1.0f}).view({4, 2});
  const torch::Tensor n = torch::tensor({0.0f, 2.0f, 0.0f, 0.5f, 0.0f, 0.0f, 1.0f, 0.3f}).view({4, 2});
  CHECK(triplet_loss(a, p, n, 0.2).item<double>() == Approx(0.265).epsilon(1e-6));
  CHECK(triplet_accuracy(a, p, n) == Approx(0.75));
  // Margin 0: only the wrong triplet counts, 0.75 / 4.
  CHECK(triplet_loss(a, p, n, 0.0).item<double>() == Approx(0.1875).epsilon(1e-6));
  // Distances in per-triplet units s = (1, 0.5, 1, 10):
  //   t0: 0.2 + (1 - 4) = -2.8 -> 0;  t1: 0.2 + 0.5 (1 - 0.25) = 0.575;  t2: 0.2 + (0 - 1) -> 0;
  //   t3: 0.2 + 10 (1 - 1.09) = -0.7 -> 0 (now outside the margin).  L_T = 0.575 / 4 = 0.14375.
  const torch::Tensor scale = torch::tensor({1.0f, 0.5f, 1.0f, 10.0f});
  CHECK(triplet_loss(a, p, n, 0.2, scale).item<double>() == Approx(0.14375).epsilon(1e-6));
  CHECK_THROWS_WITH(triplet_loss(a, p, n, 0.2, scale.slice(0, 0, 3)), Catch::Contains("expected scale [T] with T = 4"));
  // A tie (D(a,p) = D(a,n)) is not right.
  CHECK(triplet_accuracy(a.slice(0, 0, 1), p.slice(0, 0, 1), p.slice(0, 0, 1)) == 0.0);
  // No triplets: loss 0, accuracy undefined.
  const torch::Tensor none = torch::zeros({0, 2});
  CHECK(triplet_loss(none, none, none).item<double>() == 0.0);
  CHECK(std::isnan(triplet_accuracy(none, none, none)));
}

TEST_CASE("triplet_loss pulls the anchor towards the positive", "[losses]") {
  const torch::Tensor a = torch::tensor({0.0f, 0.0f}).view({1, 2}).requires_grad_();
  const torch::Tensor p = torch::tensor({1.0f, 0.0f}).view({1, 2});
  const torch::Tensor n = torch::tensor({0.0f, 0.5f}).view({1, 2});
  triplet_loss(a, p, n).backward();
  // d/da [ |a - p|^2 - |a - n|^2 ] = 2 (a - p) - 2 (a - n) = 2 (n - p) = (-2, 1): descent moves a
  // towards p and away from n.
  CHECK(torch::allclose(a.grad(), torch::tensor({-2.0f, 1.0f}).view({1, 2})));
  CHECK_THROWS_WITH(triplet_loss(a, p, n, -0.1), "triplet_loss.margin: expected a number >= 0, got -0.1");
}

}  // namespace
}  // namespace retarget
