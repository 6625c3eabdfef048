#include "translate/linear_expression_cloning.h"

#include <fmt/format.h>

#include "core/config.h"
#include "core/error.h"

namespace retarget {

void LecOptions::validate() const {
  require(ridge >= 0 && std::isfinite(ridge), "lec.ridge", fmt::format("expected a finite number >= 0, got {}", ridge));
}

TranslationMlp fit_linear_expression_cloning(const torch::Tensor& inputs, const torch::Tensor& targets,
                                             const LecOptions& options) {
  options.validate();
  if (inputs.dim() != 2 || targets.dim() != 2 || inputs.size(0) != targets.size(0) || inputs.size(0) < 1)
    throw Error("lec", fmt::format("expected inputs [N, Lh] and targets [N, La] with N >= 1, got {} and {}",
                                   c10::str(inputs.sizes()), c10::str(targets.sizes())));
  torch::NoGradGuard no_grad;
  const torch::Tensor x = inputs.to(torch::kFloat64), y = targets.to(torch::kFloat64);
  const torch::Tensor x_mean = x.mean(0), y_mean = y.mean(0);
  const torch::Tensor xc = x - x_mean, yc = y - y_mean;
  const int64_t lh = x.size(1), la = y.size(1);
  const double scale = std::max(xc.pow(2).mean().item<double>(), 1e-12);
  const torch::Tensor gram = xc.t().mm(xc) + options.ridge * scale * x.size(0) * torch::eye(lh, torch::kFloat64);
  // M^T = (X^T X + ridge)^-1 X^T Y: [Lh, La]
  const torch::Tensor mt = torch::linalg::pinv(gram).mm(xc.t().mm(yc));
  const torch::Tensor bias = y_mean - x_mean.matmul(mt);

  TranslationMlp mlp(TranslationMlpOptions().latent_in(lh).hidden(lh).latent_out(la).negative_slope(1.0));
  mlp->f1->weight.copy_(torch::eye(lh));
  mlp->f1->bias.zero_();
  for (torch::nn::Linear layer : {mlp->f2, mlp->f3}) {
    layer->weight.zero_();
    layer->bias.zero_();
  }
  mlp->g->weight.zero_();
  mlp->g->weight.narrow(1, 0, lh).copy_(mt.t().to(torch::kFloat32));
  mlp->g->bias.copy_(bias.to(torch::kFloat32));
  mlp->eval();
  return mlp;
}

}  // namespace retarget
