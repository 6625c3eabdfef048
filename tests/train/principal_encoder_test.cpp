// The encoder skip started at the principal codes: with the decoder started beside it
// (train/principal_decoder.h), the untrained VAE reconstructs low-rank data through its code,
// the code's first k coordinates are the principal coefficients, and bad input is refused.
#include "train/principal_encoder.h"

#include <catch2/catch.hpp>
#include <numeric>

#include "core/error.h"
#include "models/graph_operator.h"
#include "tests/models/model_test_support.h"
#include "train/principal_decoder.h"

namespace retarget {
namespace principal_encoder_test {

constexpr int64_t kRows = 3, kCols = 4, kV = kRows * kCols, kRank = 3, kSamples = 24, kLatent = 5;

MeshVae small_vae(bool skip) {
  const torch::Tensor l = graph_operator(test::grid_edges(kRows, kCols), kV);
  return MeshVae(l, MeshVaeOptions(kV).channels({9, 8, 1}).hidden(16).latent(kLatent).encoder_skip(skip));
}

// tanh(m + c A), c ~ N(0, 1) [M, kRank], A [kRank, V * 9]: rank kRank before the tanh.
torch::Tensor low_rank_targets() {
  const torch::Tensor m = 0.2 * torch::randn({1, kV * 9});
  const torch::Tensor a = 0.1 * torch::randn({kRank, kV * 9});
  return torch::tanh(m + torch::randn({kSamples, kRank}).mm(a)).view({kSamples, kV, 9});
}

std::vector<int64_t> all_rows() {
  std::vector<int64_t> rows(kSamples);
  std::iota(rows.begin(), rows.end(), 0);
  return rows;
}

TEST_CASE("the encoder skip adds a linear map of the input to the code's mean", "[principal_encoder]") {
  torch::manual_seed(2);
  MeshVae plain = small_vae(false), skip = small_vae(true);
  CHECK(plain->encoder_skip.is_empty());
  REQUIRE_FALSE(skip->encoder_skip.is_empty());
  CHECK(skip->encoder_skip->weight.sizes() == torch::IntArrayRef({kLatent, kV * 9}));
  int64_t counted = 0;
  for (const auto& p : skip->parameters()) counted += p.numel();
  CHECK(counted == skip->options.parameter_count());
  CHECK(skip->options.parameter_count() - plain->options.parameter_count() == kV * 9 * kLatent + kLatent);

  torch::NoGradGuard no_grad;
  const torch::Tensor x = 0.5 * torch::randn({2, kV, 9});
  const torch::Tensor before = skip->encode(x).mean;
  skip->encoder_skip->weight.zero_();
  skip->encoder_skip->bias.fill_(0.25);
  const torch::Tensor without = skip->encode(x).mean;
  skip->encoder_skip->weight[1][7] = 2.0;  // code 1 += 2 x[:, 0, 7]
  const torch::Tensor with = skip->encode(x).mean;
  CHECK((with.select(1, 1) - without.select(1, 1) - 2.0 * x.select(1, 0).select(1, 7)).abs().max().item<double>() <
        1e-6);
  CHECK((with.select(1, 0) - without.select(1, 0)).abs().max().item<double>() == 0);
  CHECK((before - without).abs().max().item<double>() > 0);
}

TEST_CASE("a VAE started at the principal codes reconstructs low-rank data before training", "[principal_encoder]") {
  torch::manual_seed(3);
  MeshVae vae = small_vae(true);
  const torch::Tensor targets = low_rank_targets();
  const PrincipalDecoderStart decoder = start_decoder_at_principal_components(*vae, targets, all_rows());
  REQUIRE(decoder.components == kRank);  // at most the latent size: kRank < kLatent
  REQUIRE(decoder.codes.sizes() == torch::IntArrayRef({kSamples, kRank}));
  CHECK(decoder.positions == all_rows());
  // The codes are unit-spread coefficients: mean 0, mean square 1 per coordinate.
  CHECK(decoder.codes.mean(0).abs().max().item<double>() < 1e-5);
  CHECK((decoder.codes.pow(2).mean(0) - 1).abs().max().item<double>() < 1e-4);

  const PrincipalEncoderStart encoder = start_encoder_at_principal_codes(*vae, targets, all_rows(), decoder.codes);
  CHECK(encoder.components == kRank);
  CHECK(encoder.fit < 0.05);  // the ridge's shrinkage, on rank-3 inputs

  torch::NoGradGuard no_grad;
  const VaeEncoding code = vae->encode(targets);
  // The code's first k coordinates are the principal codes (up to the ridge's shrinkage), the rest 0.
  CHECK((code.mean.slice(1, 0, kRank) - decoder.codes).abs().max().item<double>() < 0.1);
  CHECK(code.mean.slice(1, kRank, kLatent).abs().max().item<double>() == 0);
  CHECK((code.logvar - kStartLogVariance).abs().max().item<double>() == 0);
  // Decoded, they are the targets: the error is a small fraction of the targets' spread about their mean.
  const torch::Tensor spread = (targets - targets.mean(0)).abs().mean();
  const torch::Tensor error = (vae->decode(code.mean) - targets).abs().mean();
  CHECK(error.item<double>() < 0.05 * spread.item<double>());
  // The decoder's first k pairs are driven one to one by the code: pair i's rows are +-e_i.
  const torch::Tensor w = vae->decoder_hidden->weight;
  for (int64_t i = 0; i < kRank; ++i) {
    CHECK(w[2 * i][i].item<double>() == 1.0);
    CHECK(w[2 * i + 1][i].item<double>() == -1.0);
    CHECK(w[2 * i].abs().sum().item<double>() == 1.0);
  }
}

TEST_CASE("the encoder start refuses what it cannot use", "[principal_encoder]") {
  torch::manual_seed(5);
  MeshVae plain = small_vae(false), vae = small_vae(true);
  const torch::Tensor targets = low_rank_targets();
  const torch::Tensor codes = torch::randn({kSamples, 2});
  CHECK_THROWS_WITH(start_encoder_at_principal_codes(*plain, targets, all_rows(), codes),
                    Catch::Contains("has no encoder skip (model.encoder_skip: true)"));
  CHECK_THROWS_WITH(start_encoder_at_principal_codes(*vae, targets.view({kSamples, kV * 9}), all_rows(), codes),
                    Catch::Contains("expected inputs [M, 12, 9]"));
  CHECK_THROWS_WITH(start_encoder_at_principal_codes(*vae, targets, {0, 1}, codes),
                    Catch::Contains("expected codes [2, <= 5] for 2 rows"));
  CHECK_THROWS_WITH(start_encoder_at_principal_codes(*vae, targets, all_rows(), torch::randn({kSamples, 6})),
                    Catch::Contains("expected codes [24, <= 5]"));
  std::vector<int64_t> rows = all_rows();
  rows.back() = kSamples;
  CHECK_THROWS_WITH(start_encoder_at_principal_codes(*vae, targets, rows, codes),
                    Catch::Contains("row 24 is outside the 24 inputs"));
}

}  // namespace principal_encoder_test
}  // namespace retarget
