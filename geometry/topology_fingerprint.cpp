#include "geometry/topology_fingerprint.h"

#include <cstdint>
#include <cstdio>

namespace retarget {

namespace {
void mix(uint64_t& hash, uint32_t value) {
  for (int byte = 0; byte < 4; ++byte) {
    hash ^= (value >> (8 * byte)) & 0xffu;
    hash *= 0x100000001b3ull;
  }
}
}  // namespace

std::string topology_fingerprint(const Mesh& mesh) {
  uint64_t hash = 0xcbf29ce484222325ull;
  mix(hash, static_cast<uint32_t>(mesh.vertex_count()));
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
    for (int c = 0; c < 3; ++c) mix(hash, static_cast<uint32_t>(mesh.triangles(t, c)));
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(hash));
  return text;
}

}  // namespace retarget
