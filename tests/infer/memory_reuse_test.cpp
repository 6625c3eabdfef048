#include "infer/memory_reuse.h"

// LibTorch before Catch: glog (through c10) defines CHECK, and the last definition wins.
#include <torch/torch.h>

#include <catch2/catch.hpp>

namespace retarget {
namespace {

TEST_CASE("reuse_tensor_memory hands freed large blocks to the next tensor of that size", "[memory_reuse]") {
  reuse_tensor_memory();
  const size_t before = cached_tensor_bytes();
  void* first = nullptr;
  {
    torch::Tensor a = torch::full({1 << 21}, 1.5f);  // 8 MB
    first = a.data_ptr();
  }
  CHECK(cached_tensor_bytes() >= before + (size_t{8} << 20));
  torch::Tensor b = torch::empty({1 << 21});
  CHECK(b.data_ptr() == first);  // the same block, no new pages
  b.fill_(2.0f);
  CHECK(b.sum().item<double>() == 2.0 * (1 << 21));
  // Much smaller or larger tensors do not take it.
  torch::Tensor small = torch::ones({1000});
  CHECK(small.data_ptr() != first);
  CHECK(small.sum().item<double>() == 1000.0);

  // A cap of zero returns every idle block; the allocator keeps working.
  reuse_tensor_memory(0);
  CHECK(cached_tensor_bytes() == 0);
  b = torch::Tensor();
  CHECK(cached_tensor_bytes() == 0);
  reuse_tensor_memory();
  torch::Tensor c = torch::arange(1 << 21, torch::kFloat32);
  CHECK(c[12345].item<float>() == 12345.0f);
}

}  // namespace
}  // namespace retarget
