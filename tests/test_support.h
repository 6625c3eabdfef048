// Shared helpers for the tests: small meshes built inline and a scratch folder.
// Tests never depend on the working directory or on ../shared/data.
#pragma once

#include <cmath>
#include <filesystem>
#include <string>

#include "geometry/mesh.h"
#include "geometry/primitive_meshes.h"

namespace retarget::test {

// A fresh, empty scratch folder below the build tree, unique per name.
inline std::filesystem::path scratch_dir(const std::string& name) {
  std::filesystem::path dir = std::filesystem::path(RETARGET_TEST_TMP) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
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
