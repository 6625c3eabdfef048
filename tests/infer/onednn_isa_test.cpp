// infer/onednn_isa.h: 8-bit products held off oneDNN's AMX path, the user's choice respected, and the
// instruction set named in the benchmarks' labels. CTest runs each case in a process of its own, as
// oneDNN fixes its choice at its first kernel.
#include "infer/onednn_isa.h"

#include <catch2/catch.hpp>
#include <cstdlib>

#include "infer/retargeter_network.h"

using namespace retarget;

namespace {
bool user_chose_isa() { return std::getenv("ONEDNN_MAX_CPU_ISA") || std::getenv("DNNL_MAX_CPU_ISA"); }
}  // namespace

TEST_CASE("8-bit products run on AVX-512 VNNI, not oneDNN's AMX path, and their label says so", "[onednn]") {
  const std::string kernel = network_products_kernel(NetworkPrecision::int8);
  INFO(kernel);
  if (!network_precision_available(NetworkPrecision::int8)) {
    CHECK(kernel == "oneDNN dnnl_gemm_u8s8s32 (not on this CPU)");
    return;
  }
  CHECK(kernel == "oneDNN dnnl_gemm_u8s8s32 on " + onednn_isa());
  if (cpu_has_amx() && !user_chose_isa()) {
    CHECK(prefer_vnni_to_amx());
    CHECK(onednn_isa() == "AVX512_CORE_BF16");
  }
  CHECK((onednn_isa() != "AVX512_CORE_AMX" || user_chose_isa()));
}

TEST_CASE("an instruction set the user chose for oneDNN is kept", "[onednn]") {
  ::unsetenv("DNNL_MAX_CPU_ISA");
  ::setenv("ONEDNN_MAX_CPU_ISA", "AVX2", 1);
  CHECK_FALSE(prefer_vnni_to_amx());
  // oneDNN reads the variable at its first kernel; every CPU this project runs on has AVX2.
  const std::string isa = onednn_isa();
  CHECK((isa == "AVX2" || isa.empty()));  // empty: this LibTorch loads no oneDNN
  ::unsetenv("ONEDNN_MAX_CPU_ISA");
}
