// Helpers for the model tests: tiny mesh graphs built inline (tests/test_support.h would pull in
// geometry/, which models/ must not depend on) and a gradient check.
#pragma once

#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <cstdint>
#include <vector>

namespace retarget::test {

// Edges of a rows x cols triangulated grid (each quad split by one diagonal): [E, 2] int64.
// Not bipartite, so lambda_max of its Laplacian is below 2.
inline torch::Tensor grid_edges(int64_t rows, int64_t cols) {
  std::vector<int64_t> e;
  auto id = [cols](int64_t r, int64_t c) { return r * cols + c; };
  for (int64_t r = 0; r < rows; ++r) {
    for (int64_t c = 0; c < cols; ++c) {
      if (c + 1 < cols) e.insert(e.end(), {id(r, c), id(r, c + 1)});
      if (r + 1 < rows) e.insert(e.end(), {id(r, c), id(r + 1, c)});
      if (r + 1 < rows && c + 1 < cols) e.insert(e.end(), {id(r, c), id(r + 1, c + 1)});
    }
  }
  return torch::tensor(e, torch::kInt64).view({-1, 2});
}

// Every parameter has a gradient that is finite and not all zero.
inline void check_gradients(const torch::nn::Module& module) {
  for (const auto& p : module.named_parameters()) {
    INFO("parameter " << p.key());
    const torch::Tensor& grad = p.value().grad();
    REQUIRE(grad.defined());
    CHECK(grad.sizes() == p.value().sizes());
    CHECK(torch::isfinite(grad).all().item<bool>());
    CHECK(grad.abs().sum().item<double>() > 0.0);
  }
}

}  // namespace retarget::test
