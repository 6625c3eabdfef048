// The decoder started at its targets' principal components: an affine map of the code whose
// reach is exactly the targets' (pre-tanh) principal subspace, and clear errors for bad input.
#include "train/principal_decoder.h"

#include <catch2/catch.hpp>
#include <numeric>

#include "core/error.h"
#include "models/graph_operator.h"
#include "tests/models/model_test_support.h"

namespace retarget {
namespace principal_decoder_test {

constexpr int64_t kRows = 3, kCols = 4, kV = kRows * kCols, kRank = 3, kSamples = 20;

MeshVae small_vae() {
  const torch::Tensor l = graph_operator(test::grid_edges(kRows, kCols), kV);
  return MeshVae(l, MeshVaeOptions(kV).channels({9, 8, 1}).hidden(16).latent(4));
}

// kSamples targets [M, V, 9] = tanh(m + c A), c ~ N(0, 1) [M, kRank], A [kRank, V * 9]: rank kRank.
torch::Tensor low_rank_targets() {
  const torch::Tensor m = 0.2 * torch::randn({1, kV * 9});  // well inside the clamp (|tanh| < 0.99)
  const torch::Tensor a = 0.1 * torch::randn({kRank, kV * 9});
  const torch::Tensor x = m + torch::randn({kSamples, kRank}).mm(a);
  REQUIRE(x.abs().max().item<double>() < std::atanh(kPrincipalClamp));
  return torch::tanh(x).view({kSamples, kV, 9});
}

std::vector<int64_t> all_rows() {
  std::vector<int64_t> rows(kSamples);
  std::iota(rows.begin(), rows.end(), 0);
  return rows;
}

TEST_CASE("a decoder started at the principal components is affine in the code and reaches every target",
          "[principal_decoder]") {
  torch::manual_seed(3);
  MeshVae vae = small_vae();
  const torch::Tensor targets = low_rank_targets();
  const PrincipalDecoderStart start = start_decoder_at_principal_components(*vae, targets, all_rows());
  CHECK(start.components == kRank);
  CHECK(start.explained > 0.9999);
  CHECK(start.explained <= 1.0 + 1e-9);

  torch::NoGradGuard no_grad;
  const auto pre_tanh = [&](const torch::Tensor& z) { return torch::atanh(vae->decode(z)).view({z.size(0), -1}); };
  const torch::Tensor z1 = torch::randn({1, 4}), z2 = torch::randn({1, 4}), zero = torch::zeros({1, 4});
  CHECK((pre_tanh(z1) + pre_tanh(z2) - pre_tanh(z1 + z2) - pre_tanh(zero)).abs().max().item<double>() < 1e-4);

  // Every training target, pre-tanh, is the bias plus a combination of the decoder's columns...
  const torch::Tensor w = vae->decoder_out->weight.to(torch::kFloat64);  // [V * 9, hidden]
  const torch::Tensor rhs =
      (torch::atanh(targets.view({kSamples, -1})) - vae->decoder_out->bias).to(torch::kFloat64).t();  // [V * 9, M]
  const torch::Tensor fit = std::get<0>(torch::linalg_lstsq(w, rhs, c10::nullopt, "gelsd"));  // w is rank deficient
  CHECK((w.mm(fit) - rhs).abs().max().item<double>() < 1e-4);
  // ... and the decoder reaches nothing else: kRank pairs of opposite columns, the rest 0.
  CHECK((w.slice(1, 0, 2 * kRank, 2) + w.slice(1, 1, 2 * kRank, 2)).abs().max().item<double>() == 0);
  CHECK(w.slice(1, 2 * kRank, w.size(1)).abs().max().item<double>() == 0);
  CHECK(w.slice(1, 0, 2 * kRank).abs().min().item<double>() >= 0);
  CHECK(w.slice(1, 0, 2 * kRank).abs().sum().item<double>() > 0);
  // The bias is the targets' mean, pre-tanh.
  CHECK((vae->decoder_out->bias - torch::atanh(targets).view({kSamples, -1}).mean(0)).abs().max().item<double>() <
        1e-5);
}

TEST_CASE("the principal start takes only the given rows, and refuses what it cannot use", "[principal_decoder]") {
  torch::manual_seed(5);
  MeshVae vae = small_vae();
  torch::Tensor targets = low_rank_targets();
  // Two rows span one direction around their mean.
  CHECK(start_decoder_at_principal_components(*vae, targets, {2, 7}).components == 1);
  CHECK_THROWS_WITH(start_decoder_at_principal_components(*vae, targets, {4}),
                    Catch::Contains("needs at least 2 training rows, got 1"));
  CHECK_THROWS_WITH(start_decoder_at_principal_components(*vae, targets, {0, kSamples}),
                    Catch::Contains("row 20 is outside the 20 targets"));
  CHECK_THROWS_WITH(start_decoder_at_principal_components(*vae, targets.view({kSamples, kV * 9}), all_rows()),
                    Catch::Contains("expected targets [M, 12, 9]"));
  CHECK_THROWS_AS(start_decoder_at_principal_components(*vae, targets.slice(1, 0, 5), all_rows()), Error);
}

}  // namespace principal_decoder_test
}  // namespace retarget
