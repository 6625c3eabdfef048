#include "models/translation_mlp.h"

#include <utility>

#include "core/config.h"
#include "models/mesh_vae.h"

namespace retarget {

void TranslationMlpOptions::validate(const std::string& key_path) const {
  require_positive(static_cast<double>(latent_in_), key_path + ".latent_in");
  require_positive(static_cast<double>(hidden_), key_path + ".hidden");
  require_positive(static_cast<double>(latent_out_), key_path + ".latent_out");
  require_non_negative(negative_slope_, key_path + ".negative_slope");
  for (const auto& [value, key] :
       {std::pair{latent_in_, ".latent_in"}, std::pair{hidden_, ".hidden"}, std::pair{latent_out_, ".latent_out"}})
    require(value <= kMaxLayerWidth, key_path + key,
            "expected at most " + std::to_string(kMaxLayerWidth) + ", got " + std::to_string(value));
}

TranslationMlpImpl::TranslationMlpImpl(const TranslationMlpOptions& options_) : options(options_) {
  options.validate();
  reset();
}

void TranslationMlpImpl::reset() {
  const int64_t h = options.hidden();
  f1 = register_module("f1", torch::nn::Linear(options.latent_in(), h));
  f2 = register_module("f2", torch::nn::Linear(h, h));
  f3 = register_module("f3", torch::nn::Linear(2 * h, h));
  g = register_module("g", torch::nn::Linear(3 * h, options.latent_out()));
}

torch::Tensor TranslationMlpImpl::forward(const torch::Tensor& x) {
  TORCH_CHECK(x.dim() == 2 && x.size(1) == options.latent_in(), "TranslationMlp: expected x [B, ", options.latent_in(),
              "], got ", x.sizes());
  const double slope = options.negative_slope();
  const torch::Tensor x1 = torch::leaky_relu(f1->forward(x), slope);
  const torch::Tensor x2 = torch::leaky_relu(f2->forward(x1), slope);
  const torch::Tensor x3 = torch::leaky_relu(f3->forward(torch::cat({x1, x2}, 1)), slope);
  return g->forward(torch::cat({x1, x2, x3}, 1));
}

}  // namespace retarget
