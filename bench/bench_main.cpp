// retarget_bench's main: Google Benchmark's, with the machine in the report's context, so that a
// figure says where it comes from: ATen's CPU kernel level (DEFAULT, AVX2, AVX512), whether
// oneDNN (MKLDNN) is built in, the CPU's vector and matrix extensions from /proc/cpuinfo (avx2,
// avx512f, avx512_bf16, amx_tile, amx_bf16), the CPU model, and the environment that changes
// which kernels run (ATEN_CPU_CAPABILITY, OPENBLAS_CORETYPE, OMP_WAIT_POLICY, OMP_NUM_THREADS,
// DNNL_MAX_CPU_ISA, ONEDNN_MAX_CPU_ISA) with the instruction set oneDNN runs.
#include <ATen/Context.h>
#include <ATen/Version.h>
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "infer/onednn_isa.h"

namespace {

// ATen's own line "CPU capability usage: AVX512" from at::show_config() (the kernel level its
// dispatcher picked for this CPU and ATEN_CPU_CAPABILITY).
std::string aten_capability() {
  std::istringstream config(at::show_config());
  const std::string key = "CPU capability usage:";
  for (std::string line; std::getline(config, line);)
    if (const size_t at = line.find(key); at != std::string::npos) return line.substr(at + key.size() + 1);
  return "unknown";
}

// The model name and the flags of interest of the first CPU in /proc/cpuinfo.
void add_cpu_context() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line, model, flags;
  while (std::getline(cpuinfo, line) && (model.empty() || flags.empty())) {
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    const std::string key = line.substr(0, line.find_last_not_of(" \t", colon - 1) + 1);
    const std::string value = colon + 2 <= line.size() ? line.substr(colon + 2) : "";
    if (key == "model name" && model.empty()) model = value;
    if (key == "flags" && flags.empty()) flags = value;
  }
  std::set<std::string> present;
  std::istringstream words(flags);
  for (std::string w; words >> w;) present.insert(w);
  std::string extensions;
  for (const char* f : {"avx2", "fma", "avx512f", "avx512_vnni", "avx512_bf16", "amx_tile", "amx_bf16", "amx_int8"})
    if (present.count(f)) extensions += (extensions.empty() ? "" : " ") + std::string(f);
  benchmark::AddCustomContext("cpu_model", model.empty() ? "unknown" : model);
  benchmark::AddCustomContext("cpu_extensions", extensions.empty() ? "none of interest" : extensions);
}

void add_environment_context() {
  for (const char* name : {"ATEN_CPU_CAPABILITY", "OPENBLAS_CORETYPE", "OMP_WAIT_POLICY", "OMP_NUM_THREADS",
                           "DNNL_MAX_CPU_ISA", "ONEDNN_MAX_CPU_ISA"}) {
    const char* value = std::getenv(name);
    benchmark::AddCustomContext(name, value ? value : "(unset)");
  }
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::AddCustomContext("aten_cpu_capability", aten_capability());
  benchmark::AddCustomContext(
      "onednn", at::hasMKLDNN() ? (at::globalContext().userEnabledMkldnn() ? "built in, enabled" : "built in, disabled")
                                : "not built in");
  add_cpu_context();
  add_environment_context();
  // As retarget-infer --precision int8 does before its first 8-bit product (infer/onednn_isa.h),
  // here before any benchmark: bfloat16's rows then run without AMX too, and every label says
  // which instruction set oneDNN ran (ONEDNN_MAX_CPU_ISA=AVX512_CORE_AMX measures AMX's).
  retarget::prefer_vnni_to_amx();
  benchmark::AddCustomContext("onednn_isa", retarget::onednn_isa());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
