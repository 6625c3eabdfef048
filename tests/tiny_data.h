// Tiny rigs, face models and recipes for the tests of train/: a 36-vertex bumpy patch with
// smooth displacement fields, so datasets build in milliseconds.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "data/dataset.h"
#include "geometry/face_model.h"
#include "geometry/rig.h"
#include "test_support.h"

namespace retarget::test {

// A smooth displacement field over the patch, different for every k.
inline Positions field(const Mesh& m, int k, double scale) {
  Positions d = Positions::Zero(m.vertex_count(), 3);
  for (int v = 0; v < m.vertex_count(); ++v) {
    const double x = m.vertices(v, 0), y = m.vertices(v, 1);
    d(v, 0) = scale * std::sin(1.3 * x + k) * y;
    d(v, 1) = scale * std::cos(0.7 * y - k) * x;
    d(v, 2) = scale * std::sin(x * y + 0.5 * k);
  }
  return d;
}

inline Rig tiny_rig(int patch = 5) {
  Rig rig;
  rig.name = "blob";
  rig.units = "cm";
  rig.neutral = test::bumpy_patch(patch);  // (patch + 1)^2 vertices
  for (int k = 0; k < 4; ++k) rig.controllers.push_back({"ctrl" + std::to_string(k), field(rig.neutral, k, 0.15)});
  rig.landmarks = {{"tip", 14}};
  rig.eyes.left = {1, 2};
  rig.eyes.right = {3, 4};
  return rig;
}

inline FaceModel tiny_face_model() {
  FaceModel model;
  model.name = "tiny";
  model.source = "tiny face model";
  model.neutral = test::bumpy_patch(5);
  for (int k = 0; k < 3; ++k)
    model.identities.push_back({"id" + std::to_string(k), field(model.neutral, 10 + k, 0.08)});
  for (const char* name : {"a", "b", "c"})
    model.expressions.push_back({name, field(model.neutral, 20 + static_cast<int>(model.expressions.size()), 0.2)});
  return model;
}

inline std::vector<ExpressionRecipe> tiny_recipes() {
  return {{"neutral", {}}, {"A", {{"a", 1.0}}}, {"AB", {{"a", 0.5}, {"b", 1.0}}}, {"C", {{"c", 1.0}}}};
}

// An avatar dataset of `rig` in process_scratch_dir(name)/data (its rig in .../rig); returns the
// dataset folder. Callers keep it in a function-local static to build it once per test binary.
inline std::string build_tiny_avatar_dataset(const std::string& name, const Rig& rig, int samples, double test_fraction,
                                             uint64_t seed) {
  const std::filesystem::path dir = process_scratch_dir(name);
  write_rig_folder((dir / "rig").string(), rig);
  AvatarDatasetOptions o;
  o.samples = samples;
  o.test_fraction = test_fraction;
  o.seed = seed;
  o.progress = nullptr;
  build_avatar_dataset((dir / "rig").string(), (dir / "data").string(), o);
  return (dir / "data").string();
}

// A human dataset of the tiny face model and recipes in process_scratch_dir(name)/data.
inline std::string build_tiny_human_dataset(const std::string& name, int people, int test_people, uint64_t seed) {
  const std::filesystem::path dir = process_scratch_dir(name);
  HumanDatasetOptions o;
  o.people = people;
  o.test_people = test_people;
  o.seed = seed;
  o.progress = nullptr;
  build_human_dataset(tiny_face_model(), tiny_recipes(), "recipes.yaml", (dir / "data").string(), o);
  return (dir / "data").string();
}

}  // namespace retarget::test
