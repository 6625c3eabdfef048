#include "core/tensor_io.h"

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "scratch.h"

using namespace retarget;

using retarget::test::scratch_dir;

TEST_CASE("tensors round-trip through a file with names, dtypes and shapes", "[tensor_io]") {
  const std::string path = (scratch_dir("tensor_io") / "t.pt").string();
  const torch::Tensor features = torch::randn({3, 5, 9});
  const torch::Tensor indices = torch::arange(7, torch::kLong);
  save_tensors(path, {{"features", features}, {"indices", indices}});
  const TensorMap back = load_tensors(path);
  REQUIRE(back.size() == 2);
  CHECK(torch::equal(tensor_named(back, "features", path), features));
  CHECK(back.at("indices").dtype() == torch::kLong);
  CHECK(torch::equal(back.at("indices"), indices));
  CHECK_THROWS_WITH(tensor_named(back, "weights", path), Catch::Contains("t.pt") && Catch::Contains("\"weights\""));
}

TEST_CASE("bad tensor files are named in the error", "[tensor_io]") {
  const auto dir = scratch_dir("tensor_io_bad");
  CHECK_THROWS_WITH(load_tensors((dir / "missing.pt").string()), Catch::Contains("missing.pt"));
  std::ofstream((dir / "junk.pt").string()) << "not a tensor file";
  CHECK_THROWS_WITH(load_tensors((dir / "junk.pt").string()),
                    Catch::Contains("junk.pt") && Catch::Contains("not a LibTorch tensor file"));
}
