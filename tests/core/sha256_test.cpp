#include "core/sha256.h"

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.h"

namespace retarget {
namespace {

namespace fs = std::filesystem;

// FIPS 180-2's test vectors.
TEST_CASE("sha256 matches the standard's test vectors, in memory and from files", "[sha256]") {
  CHECK(sha256_of_bytes("abc") == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  CHECK(sha256_of_bytes("") == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  const fs::path dir = fs::path(RETARGET_TEST_TMP) / "sha256";
  fs::create_directories(dir);
  // Three million bytes: the file is read in several 1 MiB blocks.
  const std::string million_a(1000000, 'a');
  {
    std::ofstream out(dir / "a.bin", std::ios::binary | std::ios::trunc);
    for (int i = 0; i < 3; ++i) out << million_a;
  }
  CHECK(sha256_of_file((dir / "a.bin").string()) == sha256_of_bytes(million_a + million_a + million_a));
  CHECK(sha256_of_bytes(million_a) == "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  CHECK_THROWS_WITH(sha256_of_file((dir / "missing.bin").string()),
                    Catch::Contains("missing.bin") && Catch::Contains("cannot open"));
}

}  // namespace
}  // namespace retarget
