#include "models/translation_mlp.h"

#include <catch2/catch.hpp>

#include "core/error.h"
#include "tests/models/model_test_support.h"

namespace retarget {
namespace {

TEST_CASE("TranslationMlp has dense skips and trains", "[translation_mlp]") {
  torch::manual_seed(3);
  TranslationMlp net;  // 25 -> 100 -> 100 -> 100 -> 25
  CHECK(net->f1->weight.sizes() == torch::IntArrayRef({100, 25}));
  CHECK(net->f2->weight.sizes() == torch::IntArrayRef({100, 100}));
  CHECK(net->f3->weight.sizes() == torch::IntArrayRef({100, 200}));
  CHECK(net->g->weight.sizes() == torch::IntArrayRef({25, 300}));

  const torch::Tensor x = torch::randn({6, 25});
  const torch::Tensor y = net(x);
  CHECK(y.sizes() == torch::IntArrayRef({6, 25}));
  (y - torch::randn({6, 25})).pow(2).mean().backward();
  test::check_gradients(*net);

  TranslationMlp other(TranslationMlpOptions().latent_in(7).hidden(5).latent_out(3));
  CHECK(other(torch::randn({2, 7})).sizes() == torch::IntArrayRef({2, 3}));
}

TEST_CASE("TranslationMlp rejects bad options with a message", "[translation_mlp]") {
  CHECK_THROWS_WITH(TranslationMlp(TranslationMlpOptions().hidden(0)),
                    "translation_mlp.hidden: expected a positive number, got 0");
  CHECK_THROWS_WITH(TranslationMlp(TranslationMlpOptions().latent_in(-2)),
                    "translation_mlp.latent_in: expected a positive number, got -2");
  CHECK_THROWS_WITH(TranslationMlp(TranslationMlpOptions().latent_out(0)),
                    "translation_mlp.latent_out: expected a positive number, got 0");
  CHECK_THROWS_AS(TranslationMlp(TranslationMlpOptions().negative_slope(-0.5)), Error);
}

}  // namespace
}  // namespace retarget
