// A tiny morph-target animation for the glTF animation tests (tests/infer/gltf_animation_test.cpp)
// and the validator and browser checks (tests/browser/gltf_animation_fixture.cpp): a curved quad
// patch in cm (5 x 4 = 20 vertices, 12 quads) with three controllers that move different parts
// and 7 frames of weights, some outside [0, 1] (weights are written as given).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "geometry/primitive_meshes.h"
#include "infer/gltf_animation.h"

namespace retarget::test {

inline GltfAnimationInput tiny_animation(int frames = 7) {
  GltfAnimationInput in;
  in.neutral = quad_grid(4, 3, 8.0, 6.0, [](double x, double y) { return 0.5 * std::sin(x) * std::cos(y); });
  in.units = "cm";
  in.controllers = {"jawOpen", "smile Left", "brow_up.L"};
  const Positions& v = in.neutral.vertices;
  for (size_t c = 0; c < in.controllers.size(); ++c) {
    Positions offset = Positions::Zero(v.rows(), 3);
    for (Eigen::Index i = 0; i < v.rows(); ++i) {
      if (c == 0 && v(i, 1) < 3) offset.row(i) << 0, -0.75 * (3 - v(i, 1)), 0.1;       // the lower half drops
      if (c == 1 && v(i, 0) > 4) offset.row(i) << 0.3 * (v(i, 0) - 4), 0.2, -0.05;     // the right side widens
      if (c == 2 && v(i, 1) > 3) offset.row(i) << 0, 0.125 * v(i, 1), 0.01 * v(i, 0);  // the top rises
    }
    in.offsets.push_back(offset);
  }
  for (int f = 0; f < frames; ++f) {
    Eigen::VectorXd w(3);
    w << 0.5 - 0.5 * std::cos(f * 0.9), 0.125 * f, f % 3 == 0 ? 1.0 : -0.25 * (f % 3);
    in.weights.push_back(w);
  }
  return in;
}

}  // namespace retarget::test
