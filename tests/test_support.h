// Shared helpers for the tests: small meshes built inline, a scratch folder, files written
// byte for byte and the message of an expected error.
// Tests never depend on the working directory or on ../shared/data.
#pragma once

#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <system_error>
#include <vector>

#include "core/error.h"
#include "geometry/mesh.h"
#include "geometry/mesh_io.h"
#include "geometry/primitive_meshes.h"
#include "scratch.h"

namespace retarget::test {

// The message of reading the mesh file at `path` (read_mesh must refuse it).
inline std::string error_of_reading(const std::string& path) {
  return error_of([&] { read_mesh(path); });
}

using retarget::quad_grid;
using retarget::tube;
using retarget::uv_sphere;

// A curved open patch (a smooth bump over a quad grid), a stand-in for a face.
inline Mesh bumpy_patch(int n = 24) {
  return quad_grid(n, n, 2.0, 2.0, [](double x, double y) {
    const double dx = x - 1.0, dy = y - 1.0;
    return 0.6 * std::exp(-(dx * dx + dy * dy)) + 0.05 * std::sin(3 * x) * std::cos(2 * y);
  });
}

}  // namespace retarget::test
