#include "infer/onednn_isa.h"

#include <cpuid.h>
#include <dlfcn.h>
#include <fmt/format.h>

#include <cstdlib>
#include <mutex>

namespace retarget {
namespace {

// dnnl_cpu_isa_t of oneDNN 2.x (dnnl_types.h): the values dnnl_get_effective_cpu_isa returns.
constexpr int kIsaAvx512CoreBf16 = 0xe7;

struct IsaName {
  int value;
  const char* name;
};
constexpr IsaName kIsaNames[] = {{0x1, "SSE41"},
                                 {0x3, "AVX"},
                                 {0x7, "AVX2"},
                                 {0x407, "AVX2_VNNI"},
                                 {0x27, "AVX512_CORE"},
                                 {0x67, "AVX512_CORE_VNNI"},
                                 {0xe7, "AVX512_CORE_BF16"},
                                 {0x3e7, "AVX512_CORE_AMX"}};

template <class F>
F onednn_function(const char* name) {
  return reinterpret_cast<F>(dlsym(RTLD_DEFAULT, name));
}

}  // namespace

bool cpu_has_amx() {
  unsigned a = 0, b = 0, c = 0, d = 0;
  if (!__get_cpuid_count(7, 0, &a, &b, &c, &d)) return false;
  constexpr unsigned tile = 1u << 24, int8 = 1u << 25;
  return (d & tile) && (d & int8);
}

std::string onednn_isa() {
  const auto get = onednn_function<int (*)()>("dnnl_get_effective_cpu_isa");
  if (!get) return "";
  const int isa = get();
  for (const IsaName& n : kIsaNames)
    if (n.value == isa) return n.name;
  return fmt::format("0x{:x}", isa);  // a level this table does not name
}

bool prefer_vnni_to_amx() {
  static std::once_flag once;
  static bool held = false;
  std::call_once(once, [] {
    if (!cpu_has_amx() || std::getenv("ONEDNN_MAX_CPU_ISA") || std::getenv("DNNL_MAX_CPU_ISA")) return;
    const auto set = onednn_function<int (*)(int)>("dnnl_set_max_cpu_isa");
    held = set && set(kIsaAvx512CoreBf16) == 0;  // dnnl_success
  });
  return held;
}

}  // namespace retarget
