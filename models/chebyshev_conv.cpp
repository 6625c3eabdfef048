#include "models/chebyshev_conv.h"

#include <utility>
#include <vector>

#include "core/config.h"
#include "core/error.h"

namespace retarget {

void ChebyshevConvOptions::validate(const std::string& key_path) const {
  require_positive(static_cast<double>(in_), key_path + ".in");
  require_positive(static_cast<double>(out_), key_path + ".out");
  require_non_negative(static_cast<double>(order_), key_path + ".order");
}

ChebyshevConvImpl::ChebyshevConvImpl(torch::Tensor laplacian_, const ChebyshevConvOptions& options_)
    : options(options_), laplacian(std::move(laplacian_)) {
  options.validate();
  if (laplacian.dim() != 2 || laplacian.size(0) != laplacian.size(1)) {
    throw Error("chebyshev_conv", "expected a square [V, V] graph operator, got " + c10::str(laplacian.sizes()));
  }
  reset();
}

void ChebyshevConvImpl::reset() {
  laplacian = register_buffer("laplacian", laplacian);
  linear = register_module(
      "linear",
      torch::nn::Linear(
          torch::nn::LinearOptions(options.in() * (options.order() + 1), options.out()).bias(options.bias())));
}

void ChebyshevConvImpl::pretty_print(std::ostream& stream) const {
  stream << "retarget::ChebyshevConv(in=" << options.in() << ", out=" << options.out() << ", order=" << options.order()
         << ", bias=" << std::boolalpha << options.bias() << ", vertices=" << laplacian.size(0) << ")";
}

torch::Tensor ChebyshevConvImpl::forward(const torch::Tensor& x) {
  const int64_t vertices = laplacian.size(0);
  TORCH_CHECK(x.dim() == 3 && x.size(1) == vertices && x.size(2) == options.in(), "ChebyshevConv: expected x [B, ",
              vertices, ", ", options.in(), "], got ", x.sizes());
  const int64_t batch = x.size(0);
  const int64_t in = options.in();
  // [B, V, in] -> [V, B * in]: one sparse x dense product per term serves the whole batch.
  const torch::Tensor t0 = x.permute({1, 0, 2}).reshape({vertices, batch * in});
  std::vector<torch::Tensor> terms{t0};
  if (options.order() >= 1) terms.push_back(torch::mm(laplacian, t0));
  for (int64_t k = 2; k <= options.order(); ++k) {
    terms.push_back(2.0 * torch::mm(laplacian, terms[k - 1]) - terms[k - 2]);
  }
  for (auto& t : terms) t = t.view({vertices, batch, in});
  // [V, B, in * (order + 1)] -> [B, V, in * (order + 1)]
  const torch::Tensor features = torch::cat(terms, 2).permute({1, 0, 2});
  return linear->forward(features);
}

}  // namespace retarget
