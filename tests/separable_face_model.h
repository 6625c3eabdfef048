// A small face model whose identity modes and expression shapes are independent (each field has
// a frequency of its own), for tests that fit a face's expression whoever the person is.
#pragma once

#include <cmath>
#include <string>

#include "geometry/face_model.h"
#include "test_support.h"

namespace retarget::test {

// A 36-vertex face model: 3 identity modes and 3 expression shapes, smooth fields over a patch
// (test::tiny_face_model's fields span too few dimensions to tell identity from expression).
inline FaceModel separable_face_model() {
  FaceModel model;
  model.source = "small face model";
  model.neutral = test::bumpy_patch(5);
  const auto field = [&](int k, double scale) {
    Positions d(model.neutral.vertex_count(), 3);
    for (int v = 0; v < model.neutral.vertex_count(); ++v) {
      const double x = model.neutral.vertices(v, 0), y = model.neutral.vertices(v, 1);
      const double f = 0.4 + 0.23 * k;  // a frequency of its own, so no field is a mix of the others
      d.row(v) << scale * std::sin(f * x + k) * y, scale * std::cos(f * y - k) * x * x, scale * std::sin(f * x * y);
    }
    return d;
  };
  for (int k = 0; k < 3; ++k) model.identities.push_back({"id" + std::to_string(k), field(k, 0.08)});
  for (const char* name : {"a", "b", "c"})
    model.expressions.push_back({name, field(3 + static_cast<int>(model.expressions.size()), 0.2)});
  return model;
}

}  // namespace retarget::test
