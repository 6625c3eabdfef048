// What the network's graph-conv products run in (infer/retargeter_network.h runs them):
//   float32;
//   bfloat16: bfloat16 inputs, float32 sums, where the CPU has AVX512-BF16;
//   int8: each GEMM row of activations in 8 bits about its own scale (max |x| / 127), the weights
//         in 8 bits per output channel, int32 sums (oneDNN's u8s8s32 GEMM), where the CPU has
//         AVX512-VNNI.
// Everything else (DR features, the dense heads, reconstruction) stays float32 or double.
#pragma once

#include <optional>
#include <string>

namespace retarget {

enum class NetworkPrecision { float32, bfloat16, int8 };

const char* to_string(NetworkPrecision precision);  // "float32", "bfloat16", "int8"
// Those names, or "bf16"; nullopt for anything else.
std::optional<NetworkPrecision> parse_network_precision(const std::string& text);

}  // namespace retarget
