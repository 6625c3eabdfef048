// LEC (translate/linear_expression_cloning.h) is exact on pairs that are a linear map of each
// other, and is F's own network: the same forward, the same TorchScript in a bundle.
#include "translate/linear_expression_cloning.h"

#include <catch2/catch.hpp>

#include "core/error.h"
#include "scratch.h"

using namespace retarget;

TEST_CASE("LEC recovers a linear map exactly from its own pairs", "[lec]") {
  torch::manual_seed(3);
  const torch::Tensor x = torch::randn({47, 6});
  const torch::Tensor m = torch::randn({4, 6}), b = torch::randn({4});
  const torch::Tensor y = x.mm(m.t()) + b;
  LecOptions plain;
  plain.ridge = 0;
  TranslationMlp lec = fit_linear_expression_cloning(x, y, plain);
  torch::NoGradGuard no_grad;
  CHECK(torch::allclose(lec->forward(x), y, 1e-4, 1e-4));
  const torch::Tensor fresh = torch::randn({5, 6});  // a linear map holds off its pairs too
  CHECK(torch::allclose(lec->forward(fresh), fresh.mm(m.t()) + b, 1e-4, 1e-4));
  CHECK(lec->options.negative_slope() == 1.0);
  // With a ridge the map shrinks a little but still nearly reproduces its pairs.
  TranslationMlp ridged = fit_linear_expression_cloning(x, y);
  CHECK((ridged->forward(x) - y).abs().max().item<float>() < 0.05);
}

TEST_CASE("LEC refuses mismatched pairs and a negative ridge", "[lec]") {
  CHECK_THAT(test::error_of([] {
               fit_linear_expression_cloning(torch::zeros({3, 2}), torch::zeros({4, 2}));
             }),
             Catch::Contains("expected inputs [N, Lh] and targets [N, La]"));
  LecOptions bad;
  bad.ridge = -1;
  CHECK_THAT(test::error_of([&] {
               fit_linear_expression_cloning(torch::zeros({3, 2}), torch::zeros({3, 2}), bad);
             }),
             Catch::Contains("lec.ridge"));
}
