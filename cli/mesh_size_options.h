// --max-vertices and --max-faces (geometry/mesh_size_limits.h) for the commands that take a mesh
// into dense per-vertex work: `retarget avatar init` and `retarget dataset`.
#pragma once

#include <cxxopts.hpp>

#include "geometry/mesh_size_limits.h"

namespace retarget::cli {

// Adds the two options, with MeshSizeLimits' defaults.
void add_mesh_size_options(cxxopts::Options& options);

// The limits the options give (validated: throws retarget::Error naming the option).
MeshSizeLimits mesh_size_limits(const cxxopts::ParseResult& args);

}  // namespace retarget::cli
