// The translation network F from human latent codes to avatar latent codes (method notes,
// "Networks"): 25 -> 100 -> 100 -> 100 -> 25 with dense skip connections,
//   x1 = act(f1(x)), x2 = act(f2(x1)), x3 = act(f3([x1, x2])), out = g([x1, x2, x3])
// act = LeakyReLU; the output layer is linear (codes are unbounded encoder means).
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <string>

namespace retarget {

struct TranslationMlpOptions {
  void validate(const std::string& key_path = "translation_mlp") const;  // throws retarget::Error

  TORCH_ARG(int64_t, latent_in) = 25;       // human latent size, > 0
  TORCH_ARG(int64_t, hidden) = 100;         // width of the three hidden layers, > 0
  TORCH_ARG(int64_t, latent_out) = 25;      // avatar latent size, > 0
  TORCH_ARG(double, negative_slope) = 0.1;  // LeakyReLU slope, >= 0 (0.1 as in the VAEs)
};

class TranslationMlpImpl : public torch::nn::Cloneable<TranslationMlpImpl> {
 public:
  explicit TranslationMlpImpl(const TranslationMlpOptions& options = {});

  void reset() override;

  // x: [B, latent_in] float32 -> [B, latent_out].
  torch::Tensor forward(const torch::Tensor& x);

  TranslationMlpOptions options;
  torch::nn::Linear f1{nullptr}, f2{nullptr}, f3{nullptr}, g{nullptr};
};

TORCH_MODULE(TranslationMlp);

}  // namespace retarget
