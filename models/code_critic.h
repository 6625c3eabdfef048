// A small network from latent codes to one number, the CycleGAN+LFD baseline's two kinds of
// judge (translate/cyclegan_trainer.h): a discriminator (one code -> real or translated, a raw
// score for the least-squares GAN loss) and the light-field similarity regressor (a human code
// and an avatar code side by side -> their normalised light-field distance, through a sigmoid
// outside). in -> hidden -> hidden -> 1, LeakyReLU between.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <string>

namespace retarget {

struct CodeCriticOptions {
  void validate(const std::string& key_path = "critic") const;  // throws retarget::Error

  TORCH_ARG(int64_t, in) = 25;              // input width (a code, or two codes concatenated), > 0
  TORCH_ARG(int64_t, hidden) = 64;          // > 0
  TORCH_ARG(double, negative_slope) = 0.2;  // LeakyReLU slope, >= 0
};

class CodeCriticImpl : public torch::nn::Cloneable<CodeCriticImpl> {
 public:
  explicit CodeCriticImpl(const CodeCriticOptions& options = {});

  void reset() override;

  // x: [B, in] float32 -> [B] raw scores.
  torch::Tensor forward(const torch::Tensor& x);

  CodeCriticOptions options;
  torch::nn::Linear l1{nullptr}, l2{nullptr}, out{nullptr};
};

TORCH_MODULE(CodeCritic);

}  // namespace retarget
