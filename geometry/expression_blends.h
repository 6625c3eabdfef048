// Random blends of a face model's expression shapes: the unseen expressions of the evaluation.
// A performance is made of blends nobody annotated, never exactly the reference recipes, so the
// end-to-end check scores these beside the references (`retarget faces --blends N`).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "geometry/face_model.h"

namespace retarget {

struct BlendOptions {
  static constexpr int kMaxBlends = 100000;  // each is a mesh per person: more is a typo, not a test set
  int count = 0;                             // blends to make; 0..kMaxBlends
  int min_shapes = 1;                        // each blend activates k ~ uniform{min_shapes..max_shapes} distinct shapes
  int max_shapes = 4;                        //   (clamped to the shapes available); 1 <= min <= max
  double min_weight = 0.3;                   // each active shape's weight ~ U(min_weight, max_weight]; 0 < min <= max
  double max_weight = 1.0;
  uint64_t seed = 1;             // same seed and shapes, same blends on every machine
  std::string prefix = "blend";  // names <prefix>000, <prefix>001, ...

  // Throws retarget::Error naming `key_path`.<field> for a value out of range.
  void validate(const std::string& key_path = "blends") const;
};

// options.count blends of `shapes` (blendshape names, e.g. FaceModel::expressions' names), each a
// recipe {name, weights}. Shapes are picked uniformly without repetition (Random::below), weights
// with Random::uniform (core/random.h), so the result is a function of the seed and the list.
// A blend whose shapes and weights all lie within 0.05 of one of `avoid`'s recipes (the
// references) is drawn again, so none of them is a reference in disguise.
// Throws retarget::Error for invalid options or an empty shape list with count > 0.
std::vector<ExpressionRecipe> random_blends(const std::vector<std::string>& shapes, const BlendOptions& options,
                                            const std::vector<ExpressionRecipe>& avoid = {});

}  // namespace retarget
