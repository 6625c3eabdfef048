#include "geometry/mesh_size_limits.h"

#include <fmt/format.h>

#include "core/error.h"

namespace retarget {

void MeshSizeLimits::validate() const {
  if (max_vertices < 1) throw Error("--max-vertices", fmt::format("expected a count >= 1, got {}", max_vertices));
  if (max_faces < 1) throw Error("--max-faces", fmt::format("expected a count >= 1, got {}", max_faces));
}

void check_mesh_size(const Mesh& mesh, const MeshSizeLimits& limits, const std::string& what) {
  const std::string where = mesh.source.empty() ? what : mesh.source;
  const auto refuse = [&](int64_t count, const char* noun, int64_t limit, const char* option) {
    throw Error(where, fmt::format("{} {}, more than the limit of {} (it keeps memory and time in bounds); "
                                   "decimate the mesh, or raise the limit with {} {}",
                                   count, noun, limit, option, count));
  };
  const int64_t vertices = mesh.vertex_count();
  const auto faces = static_cast<int64_t>(mesh.faces.size());
  if (vertices > limits.max_vertices) refuse(vertices, "vertices", limits.max_vertices, "--max-vertices");
  if (faces > limits.max_faces) refuse(faces, "faces", limits.max_faces, "--max-faces");
}

}  // namespace retarget
