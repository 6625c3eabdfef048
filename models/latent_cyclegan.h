// The networks of the CycleGAN+LFD baseline (translate/cyclegan_trainer.h; the paper's section
// 6.3.1 after its reference [44]), in one module so that one checkpoint holds them all:
//   to_avatar       G: human code [B, Lh] -> avatar code [B, La], F's architecture
//                   (models/translation_mlp.h), so that its bundle runs wherever F's does
//   to_human        G': avatar code -> human code, the same architecture the other way
//   avatar_critic   D_a: avatar code -> raw score (real avatar codes 1, translated 0)
//   human_critic    D_h: human code -> raw score
//   similarity      S: [human code, avatar code] -> logit of their normalised light-field
//                   distance (sigmoid: 0 alike .. 1 unlike), fitted first and then held fixed
#pragma once

#include <torch/torch.h>

#include "models/code_critic.h"
#include "models/translation_mlp.h"

namespace retarget {

struct LatentCycleGanOptions {
  TranslationMlpOptions generator;  // latent_in = Lh, latent_out = La (to_human swaps them)
  int64_t critic_hidden = 64;
};

class LatentCycleGanImpl : public torch::nn::Module {
 public:
  explicit LatentCycleGanImpl(const LatentCycleGanOptions& options);

  // sigmoid(S([human, avatar])): [B] in (0, 1), the predicted normalised light-field distance.
  torch::Tensor distance(const torch::Tensor& human, const torch::Tensor& avatar);

  LatentCycleGanOptions options;
  TranslationMlp to_avatar{nullptr}, to_human{nullptr};
  CodeCritic avatar_critic{nullptr}, human_critic{nullptr}, similarity{nullptr};
};

TORCH_MODULE(LatentCycleGan);

}  // namespace retarget
