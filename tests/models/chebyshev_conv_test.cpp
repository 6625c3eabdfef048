#include "models/chebyshev_conv.h"

#include <catch2/catch.hpp>
#include <vector>

#include "core/error.h"
#include "models/graph_operator.h"
#include "tests/models/model_test_support.h"

namespace retarget {
namespace {

// Dense reference with torch::matmul on the dense L~: [T0 x | ... | T_order x] W^T + b.
torch::Tensor dense_reference(const torch::Tensor& l, const torch::Tensor& x, ChebyshevConvImpl& conv) {
  std::vector<torch::Tensor> t{x};
  if (conv.options.order() >= 1) t.push_back(torch::matmul(l, x));
  for (int64_t k = 2; k <= conv.options.order(); ++k) t.push_back(2 * torch::matmul(l, t[k - 1]) - t[k - 2]);
  torch::Tensor y = torch::matmul(torch::cat(t, -1), conv.linear->weight.t());
  if (conv.options.bias()) y = y + conv.linear->bias;
  return y;
}

TEST_CASE("ChebyshevConv equals a dense reference", "[chebyshev_conv]") {
  torch::manual_seed(1);
  const torch::Tensor l = graph_operator(test::grid_edges(3, 4), 12);
  const auto [order, bias] = GENERATE(table<int64_t, bool>({{2, true}, {0, true}, {1, false}, {3, true}}));
  INFO("order " << order << ", bias " << bias);
  ChebyshevConv conv(l, ChebyshevConvOptions(3, 5).order(order).bias(bias));
  const torch::Tensor x = torch::randn({4, 12, 3});
  const torch::Tensor y = conv(x);
  CHECK(y.sizes() == torch::IntArrayRef({4, 12, 5}));
  torch::NoGradGuard no_grad;
  CHECK(torch::allclose(y, dense_reference(l.to_dense(), x, *conv), 1e-5, 1e-5));
  // A dense operator gives the same result as the sparse one.
  ChebyshevConv dense_conv(l.to_dense(), conv->options);
  dense_conv->linear->weight.copy_(conv->linear->weight);
  if (bias) dense_conv->linear->bias.copy_(conv->linear->bias);
  CHECK(torch::allclose(dense_conv(x), y, 1e-5, 1e-5));
}

TEST_CASE("ChebyshevConv's sparse kernels match the dense path in values and gradients", "[chebyshev_conv]") {
  // Widening layers take the terms-first path, narrowing ones the linear-first (Clenshaw) path;
  // both have hand-written backward passes.
  torch::manual_seed(2);
  const torch::Tensor l = graph_operator(test::grid_edges(4, 5), 20);
  const auto [in, out, order] =
      GENERATE(table<int64_t, int64_t, int64_t>({{3, 5, 2}, {6, 2, 2}, {8, 1, 3}, {5, 5, 1}, {7, 3, 1}}));
  INFO("in " << in << ", out " << out << ", order " << order);
  ChebyshevConv sparse(l, ChebyshevConvOptions(in, out).order(order));
  ChebyshevConv dense(l.to_dense(), sparse->options);
  {
    torch::NoGradGuard no_grad;
    dense->linear->weight.copy_(sparse->linear->weight);
    dense->linear->bias.copy_(sparse->linear->bias);
  }
  const torch::Tensor x = torch::randn({3, 20, in});
  const torch::Tensor xs = x.clone().requires_grad_(true), xd = x.clone().requires_grad_(true);
  const torch::Tensor upstream = torch::randn({3, 20, out});
  const torch::Tensor ys = sparse(xs), yd = dense(xd);
  CHECK(torch::allclose(ys, yd, 1e-5, 1e-5));
  (ys * upstream).sum().backward();
  (yd * upstream).sum().backward();
  CHECK(torch::allclose(xs.grad(), xd.grad(), 1e-5, 1e-5));
  CHECK(torch::allclose(sparse->linear->weight.grad(), dense->linear->weight.grad(), 1e-4, 1e-5));
  CHECK(torch::allclose(sparse->linear->bias.grad(), dense->linear->bias.grad(), 1e-4, 1e-5));
}

TEST_CASE("ChebyshevConv keeps the operator as a buffer and trains", "[chebyshev_conv]") {
  torch::manual_seed(2);
  const torch::Tensor l = graph_operator(test::grid_edges(2, 5), 10);
  ChebyshevConv conv(l, ChebyshevConvOptions(2, 3));
  const auto buffers = conv->named_buffers();
  REQUIRE(buffers.contains("laplacian"));
  CHECK(buffers["laplacian"].is_sparse());
  CHECK(conv->named_parameters().size() == 2);  // linear.weight, linear.bias
  CHECK(conv->linear->weight.sizes() == torch::IntArrayRef({3, 6}));

  const torch::Tensor x = torch::randn({2, 10, 2}, torch::requires_grad());
  conv(x).pow(2).sum().backward();
  test::check_gradients(*conv);
  CHECK(torch::isfinite(x.grad()).all().item<bool>());

  SECTION("clone copies weights and operator") {
    auto copy = std::dynamic_pointer_cast<ChebyshevConvImpl>(conv->clone());
    REQUIRE(copy);
    torch::NoGradGuard no_grad;
    CHECK(torch::allclose(copy->forward(x), conv(x)));
  }
}

TEST_CASE("ChebyshevConv rejects bad options with a message", "[chebyshev_conv]") {
  const torch::Tensor l = graph_operator(test::grid_edges(2, 2), 4);
  CHECK_THROWS_WITH(ChebyshevConv(l, ChebyshevConvOptions(0, 4)),
                    "chebyshev_conv.in: expected a positive number, got 0");
  CHECK_THROWS_WITH(ChebyshevConv(l, ChebyshevConvOptions(2, -1)),
                    "chebyshev_conv.out: expected a positive number, got -1");
  CHECK_THROWS_WITH(ChebyshevConv(l, ChebyshevConvOptions(2, 2).order(-1)),
                    "chebyshev_conv.order: expected a number >= 0, got -1");
  CHECK_THROWS_AS(ChebyshevConv(torch::zeros({4, 3}), ChebyshevConvOptions(2, 2)), Error);
}

}  // namespace
}  // namespace retarget
