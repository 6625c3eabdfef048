#include "train/principal_decoder.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/error.h"
#include "train/centred_gram.h"

namespace retarget {

namespace principal_decoder {

// At most this many rows enter the Gram matrix ([N, N] float64: 128 MiB); more are thinned evenly.
constexpr size_t kMaxRows = 4096;
// Eigenvalues below this fraction of the largest are the float32 products' rounding, not data.
constexpr double kRankTolerance = 1e-6;

// Columns [begin, end) of the chosen rows, pre-tanh, as float32 [N, end - begin].
torch::Tensor pre_tanh_block(const torch::Tensor& flat, const torch::Tensor& rows, int64_t begin, int64_t end) {
  return torch::atanh(flat.slice(1, begin, end).index_select(0, rows).clamp(-kPrincipalClamp, kPrincipalClamp))
      .to(torch::kFloat32);
}

}  // namespace principal_decoder

PrincipalDecoderStart start_decoder_at_principal_components(MeshVaeImpl& vae, const torch::Tensor& targets,
                                                            const std::vector<int64_t>& rows) {
  using principal_decoder::kMaxRows;
  using principal_decoder::kRankTolerance;
  using principal_decoder::pre_tanh_block;
  const int64_t V = vae.options.vertices(), F = vae.options.features(), H = vae.options.hidden();
  const int64_t D = V * F;
  if (!targets.defined() || targets.dim() != 3 || targets.size(1) != V || targets.size(2) != F)
    throw Error("principal decoder start",
                fmt::format("expected targets [M, {}, {}], got {}", V, F,
                            targets.defined() ? fmt::format("{}", fmt::join(targets.sizes(), ", ")) : "none"));
  if (rows.size() < 2)
    throw Error("principal decoder start", fmt::format("needs at least 2 training rows, got {}", rows.size()));
  for (int64_t r : rows)
    if (r < 0 || r >= targets.size(0))
      throw Error("principal decoder start", fmt::format("row {} is outside the {} targets", r, targets.size(0)));

  // The rows used: every one, or kMaxRows evenly spaced; positions[j] is taken[j]'s place in rows.
  const size_t n = std::min(rows.size(), kMaxRows);
  std::vector<int64_t> positions(n), taken(n);
  for (size_t i = 0; i < n; ++i) {
    positions[i] = static_cast<int64_t>(i * rows.size() / n);
    taken[i] = rows[static_cast<size_t>(positions[i])];
  }
  const auto N = static_cast<int64_t>(n);

  torch::NoGradGuard no_grad;
  const torch::Tensor flat = targets.reshape({targets.size(0), D});
  const torch::Tensor index = torch::tensor(taken, torch::kInt64);
  const auto block = [&](int64_t begin, int64_t end) { return pre_tanh_block(flat, index, begin, end); };

  // Pass 1: the mean and the rows' Gram matrix of the centred targets.
  const auto [mean, gram] = centred_gram(D, N, block);
  const double total = gram.trace().item<double>();

  // The leading eigenpairs: as many as the decoder's hidden pairs hold, above rounding noise.
  const auto [values, vectors] = torch::linalg_eigh(gram);  // ascending
  const double largest = values[N - 1].item<double>();
  // With an encoder skip the code drives the first pairs one to one, so only latent of them.
  const bool aligned = !vae.encoder_skip.is_empty();
  const int64_t room = std::min<int64_t>(aligned ? std::min(H / 2, vae.options.latent()) : H / 2, N);
  int64_t k = 0;
  double kept = 0;
  while (k < room && largest > 0 && values[N - 1 - k].item<double>() > kRankTolerance * largest)
    kept += values[N - 1 - k++].item<double>();

  // Pass 2: direction i's pair of columns, +-(Z^T u_i) / (1.1 sqrt(N)) = +-s_i v_i / 1.1.
  torch::Tensor weight = vae.decoder_out->weight;  // [D, H], written in place
  weight.zero_();
  if (k > 0) {
    const torch::Tensor u = vectors.slice(1, N - k, N).flip({1}).to(torch::kFloat32);  // [N, k], largest first
    const double scale = 1.0 / ((1.0 + kMeshVaeSlope) * std::sqrt(static_cast<double>(N)));
    for (int64_t begin = 0; begin < D; begin += kColumnBlock) {
      const int64_t end = std::min(D, begin + kColumnBlock);
      torch::Tensor z = block(begin, end);
      z.sub_(mean.slice(0, begin, end));
      const torch::Tensor columns = z.t().mm(u).mul_(scale);  // [block, k]
      torch::Tensor rows_block = weight.slice(0, begin, end);
      rows_block.slice(1, 0, 2 * k, 2).copy_(columns);
      rows_block.slice(1, 1, 2 * k, 2).copy_(-columns);
    }
  }
  torch::Tensor w = vae.decoder_hidden->weight, b = vae.decoder_hidden->bias;
  if (aligned && k > 0) {  // pair i = (z_i, -z_i): a_i(z) = z_i
    w.slice(0, 0, 2 * k).zero_();
    b.slice(0, 0, 2 * k).zero_();
    const torch::Tensor i = torch::arange(k, torch::kInt64);
    w.index_put_({2 * i, i}, 1.0);
    w.index_put_({2 * i + 1, i}, -1.0);
  } else {
    w.slice(0, 1, 2 * k, 2).copy_(-w.slice(0, 0, 2 * k, 2));
    b.slice(0, 1, 2 * k, 2).copy_(-b.slice(0, 0, 2 * k, 2));
  }
  vae.decoder_out->bias.copy_(mean);
  PrincipalDecoderStart start{k, total > 0 ? std::min(1.0, kept / total) : 0.0, {}, std::move(positions)};
  // Row r's coefficients along the k directions in units of their spread: sqrt(N) u_i[r].
  if (k > 0)
    start.codes = vectors.slice(1, N - k, N).flip({1}).mul(std::sqrt(static_cast<double>(N))).to(torch::kFloat32);
  return start;
}

}  // namespace retarget
