#include "infer/network_precision.h"

namespace retarget {

const char* to_string(NetworkPrecision precision) {
  switch (precision) {
    case NetworkPrecision::bfloat16:
      return "bfloat16";
    case NetworkPrecision::int8:
      return "int8";
    default:
      return "float32";
  }
}

std::optional<NetworkPrecision> parse_network_precision(const std::string& text) {
  for (NetworkPrecision p : {NetworkPrecision::float32, NetworkPrecision::bfloat16, NetworkPrecision::int8})
    if (text == to_string(p)) return p;
  if (text == "bf16") return NetworkPrecision::bfloat16;
  return std::nullopt;
}

}  // namespace retarget
