#include "core/error.h"

#include <c10/util/Exception.h>
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <functional>
#include <new>
#include <stdexcept>
#include <string>

namespace retarget {
namespace {

std::string described(const std::function<void()>& f) {
  try {
    f();
  } catch (...) {
    return describe_current_exception();
  }
  return "(nothing thrown)";
}

TEST_CASE("errors render 'where: what'", "[error]") {
  const Error e("a.obj:3", "bad vertex");
  CHECK(std::string(e.what()) == "a.obj:3: bad vertex");
  CHECK(e.where() == "a.obj:3");
  CHECK(e.detail() == "bad vertex");
  CHECK(std::string(Error("plain").what()) == "plain");
}

TEST_CASE("exceptions that reach main are described by kind, without LibTorch's backtrace", "[error]") {
  CHECK(described([] { throw Error("c.yaml:2: data.dataset", "not found"); }) == "c.yaml:2: data.dataset: not found");
  CHECK_THAT(described([] { throw std::bad_alloc(); }), Catch::StartsWith("out of memory (std::bad_alloc)"));
  // A real LibTorch failure: an impossible allocation.
  const std::string torch_error = described([] { (void)torch::empty({int64_t{1} << 62}); });
  CHECK_THAT(torch_error, Catch::StartsWith("LibTorch error: ") || Catch::StartsWith("out of memory"));
  CHECK_THAT(torch_error, !Catch::Contains("Exception raised from"));
  const std::string shape_error = described([] { (void)torch::ones({2, 3}).matmul(torch::ones({2, 3})); });
  CHECK_THAT(shape_error, Catch::StartsWith("LibTorch error: ") && !Catch::Contains("frame #"));
  CHECK(described([] { throw std::logic_error("broken"); }) == "unexpected error: broken");
  CHECK(described([] { throw 7; }) == "unexpected error of an unknown kind");
}

}  // namespace
}  // namespace retarget
