#include "models/latent_cyclegan.h"

namespace retarget {

LatentCycleGanImpl::LatentCycleGanImpl(const LatentCycleGanOptions& options_) : options(options_) {
  const TranslationMlpOptions& g = options.generator;
  TranslationMlpOptions back = g;
  back.latent_in(g.latent_out()).latent_out(g.latent_in());
  to_avatar = register_module("to_avatar", TranslationMlp(g));
  to_human = register_module("to_human", TranslationMlp(back));
  avatar_critic = register_module("avatar_critic",
                                  CodeCritic(CodeCriticOptions().in(g.latent_out()).hidden(options.critic_hidden)));
  human_critic =
      register_module("human_critic", CodeCritic(CodeCriticOptions().in(g.latent_in()).hidden(options.critic_hidden)));
  similarity = register_module(
      "similarity", CodeCritic(CodeCriticOptions().in(g.latent_in() + g.latent_out()).hidden(options.critic_hidden)));
}

torch::Tensor LatentCycleGanImpl::distance(const torch::Tensor& human, const torch::Tensor& avatar) {
  return torch::sigmoid(similarity->forward(torch::cat({human, avatar}, 1)));
}

}  // namespace retarget
