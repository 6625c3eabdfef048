// oneDNN's instruction set: which one the GEMMs of the native network (infer/retargeter_network.h)
// run on, and the choice of AVX-512 VNNI over AMX for its 8-bit products. oneDNN is the library
// LibTorch loads; it is found at run time (dlsym), so nothing here needs its headers, and every
// function answers sensibly without it.
//
// Why the choice: oneDNN 2.6 (Debian's, which LibTorch 1.13 loads) sends dnnl_gemm_u8s8s32 on a CPU
// with AMX down a path that is slow for the graph convs' blocks (512 GEMM rows, 96-384 deep, 32-64
// wide) and fixes each result up in a scalar loop. On a 2-core Intel Xeon with AMX (family 6 model
// 207), one thread, a block took 80-140 us there, 10-66 us with oneDNN held at AVX512_CORE_BF16,
// and 32-179 us in float32's sgemm (docs/experiments/2026-11-28-amx-int8.md).
#pragma once

#include <string>

namespace retarget {

// Whether this CPU has AMX's 8-bit tiles (CPUID leaf 7: AMX-TILE and AMX-INT8).
bool cpu_has_amx();

// oneDNN's instruction set in this process, by its own name ("AVX512_CORE_AMX",
// "AVX512_CORE_BF16", "AVX2"...); "" when LibTorch loaded no oneDNN. Asking fixes the choice:
// call prefer_vnni_to_amx first.
std::string onednn_isa();

// Holds oneDNN at AVX512_CORE_BF16 (AVX-512 with VNNI and BF16 dot products, no AMX) where the CPU
// has AMX, unless the user chose with ONEDNN_MAX_CPU_ISA or DNNL_MAX_CPU_ISA. oneDNN takes the
// setting only before its first kernel in the process; returns whether the hold is in force
// (false: no AMX here, the user chose, no oneDNN, or oneDNN had already chosen). float32's sgemm
// never uses AMX; bfloat16's products lose it (slower on the same Xeon: the record above).
bool prefer_vnni_to_amx();

}  // namespace retarget
