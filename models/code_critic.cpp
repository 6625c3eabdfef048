#include "models/code_critic.h"

#include "core/config.h"
#include "models/mesh_vae.h"

namespace retarget {

void CodeCriticOptions::validate(const std::string& key_path) const {
  require_positive(static_cast<double>(in_), key_path + ".in");
  require_positive(static_cast<double>(hidden_), key_path + ".hidden");
  require_non_negative(negative_slope_, key_path + ".negative_slope");
  for (const auto& [value, key] : {std::pair{in_, ".in"}, std::pair{hidden_, ".hidden"}})
    require(value <= kMaxLayerWidth, key_path + key,
            "expected at most " + std::to_string(kMaxLayerWidth) + ", got " + std::to_string(value));
}

CodeCriticImpl::CodeCriticImpl(const CodeCriticOptions& options_) : options(options_) {
  options.validate();
  reset();
}

void CodeCriticImpl::reset() {
  l1 = register_module("l1", torch::nn::Linear(options.in(), options.hidden()));
  l2 = register_module("l2", torch::nn::Linear(options.hidden(), options.hidden()));
  out = register_module("out", torch::nn::Linear(options.hidden(), 1));
}

torch::Tensor CodeCriticImpl::forward(const torch::Tensor& x) {
  TORCH_CHECK(x.dim() == 2 && x.size(1) == options.in(), "CodeCritic: expected x [B, ", options.in(), "], got ",
              x.sizes());
  const double slope = options.negative_slope();
  const torch::Tensor h = torch::leaky_relu(l2->forward(torch::leaky_relu(l1->forward(x), slope)), slope);
  return out->forward(h).squeeze(1);
}

}  // namespace retarget
