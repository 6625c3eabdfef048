#include "train/principal_encoder.h"

#include <fmt/format.h>

#include <algorithm>

#include "core/error.h"
#include "train/centred_gram.h"

namespace retarget {

PrincipalEncoderStart start_encoder_at_principal_codes(MeshVaeImpl& vae, const torch::Tensor& inputs,
                                                       const std::vector<int64_t>& rows, const torch::Tensor& codes) {
  const char* where = "principal encoder start";
  const int64_t V = vae.options.vertices(), F = vae.options.features(), L = vae.options.latent();
  const int64_t D = V * F;
  if (vae.encoder_skip.is_empty())
    throw Error(where, "the VAE has no encoder skip (model.encoder_skip: true) to start");
  if (!inputs.defined() || inputs.dim() != 3 || inputs.size(1) != V || inputs.size(2) != F)
    throw Error(where, fmt::format("expected inputs [M, {}, {}], got {}", V, F,
                                   inputs.defined() ? fmt::format("{}", fmt::join(inputs.sizes(), ", ")) : "none"));
  const auto N = static_cast<int64_t>(rows.size());
  if (!codes.defined() || codes.dim() != 2 || codes.size(0) != N || codes.size(1) > L || N < 2)
    throw Error(where, fmt::format("expected codes [{}, <= {}] for {} rows (at least 2), got {}", N, L, N,
                                   codes.defined() ? fmt::format("{}", fmt::join(codes.sizes(), ", ")) : "none"));
  for (int64_t r : rows)
    if (r < 0 || r >= inputs.size(0))
      throw Error(where, fmt::format("row {} is outside the {} inputs", r, inputs.size(0)));
  const int64_t k = codes.size(1);

  torch::NoGradGuard no_grad;
  const torch::Tensor flat = inputs.reshape({inputs.size(0), D});
  const torch::Tensor index = torch::tensor(rows, torch::kInt64);
  auto block = [&](int64_t begin, int64_t end) {
    return flat.slice(1, begin, end).index_select(0, index).to(torch::kFloat32);
  };

  // Pass 1: the inputs' mean and the centred rows' Gram matrix.
  const auto [mean, gram] = centred_gram(D, N, block);
  const double lambda = std::max(kRidge * gram.trace().item<double>() / static_cast<double>(N), 1e-12);
  const torch::Tensor c = codes.to(torch::kFloat64);
  const torch::Tensor a = torch::linalg_solve(gram + lambda * torch::eye(N, torch::kFloat64), c);  // [N, k]
  PrincipalEncoderStart start;
  start.components = k;
  start.fit = (gram.mm(a) - c).pow(2).mean().item<double>();

  // Pass 2: W = A^T X_c, block by block; the bias makes the mean input's code 0.
  torch::Tensor weight = vae.encoder_skip->weight;  // [L, D], written in place
  torch::Tensor bias = vae.encoder_skip->bias;
  weight.zero_();
  bias.zero_();
  const torch::Tensor a32 = a.to(torch::kFloat32);
  for (int64_t begin = 0; begin < D; begin += kColumnBlock) {
    const int64_t end = std::min(D, begin + kColumnBlock);
    torch::Tensor x = block(begin, end);
    x.sub_(mean.slice(0, begin, end));
    weight.slice(0, 0, k).slice(1, begin, end).copy_(a32.t().mm(x));
  }
  bias.slice(0, 0, k).copy_(-weight.slice(0, 0, k).mv(mean));
  vae.mean_head->weight.zero_();
  vae.mean_head->bias.zero_();
  vae.logvar_head->weight.zero_();
  vae.logvar_head->bias.fill_(kStartLogVariance);
  return start;
}

}  // namespace retarget
