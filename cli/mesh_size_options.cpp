#include "cli/mesh_size_options.h"

#include <string>

namespace retarget::cli {

void add_mesh_size_options(cxxopts::Options& options) {
  const MeshSizeLimits defaults;
  options.add_options()("max-vertices", "refuse a mesh with more vertices than this, before any work",
                        cxxopts::value<int64_t>()->default_value(std::to_string(defaults.max_vertices)))(
      "max-faces", "refuse a mesh with more faces than this, before any work",
      cxxopts::value<int64_t>()->default_value(std::to_string(defaults.max_faces)));
}

MeshSizeLimits mesh_size_limits(const cxxopts::ParseResult& args) {
  MeshSizeLimits limits;
  limits.max_vertices = args["max-vertices"].as<int64_t>();
  limits.max_faces = args["max-faces"].as<int64_t>();
  limits.validate();
  return limits;
}

}  // namespace retarget::cli
