// The one normalisation of DR features in the project (method notes): every dimension, per
// vertex and channel, is mapped min-max to [-0.9, 0.9] with ranges from the training split
// only. Features are already S - I (the rest pose is all zeros); the decoders end in tanh,
// so the margin to +-1 leaves room for test data a little outside the training range.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <string>
#include <vector>

#include "bundle/normalisation.h"

namespace retarget {

struct Normaliser {
  torch::Tensor min;  // [V, 9] float32, raw DR units (radians, stretch)
  torch::Tensor max;  // [V, 9] float32, max - min >= kMinimumRange everywhere

  // Per (vertex, channel) min and max over the samples of train_features ([N, V, 9], N >= 1,
  // any floating dtype); a range below kMinimumRange is widened symmetrically about its centre.
  // Throws retarget::Error for an empty set or NaN/Inf values.
  static Normaliser fit(const torch::Tensor& train_features);
  // The same over the given rows of features ([N, V, 9]) and, if defined, every sample of
  // `extra` ([M, V, 9]), without copying them all: equal to fit(cat(features[rows], extra)).
  static Normaliser fit(const torch::Tensor& features, const std::vector<int64_t>& rows,
                        const torch::Tensor& extra = {});

  int64_t vertex_count() const { return min.defined() ? min.size(0) : 0; }

  // These ranges, each widened symmetrically about its centre to at least `fraction` x the same
  // dimension's range in `reference` (same shape; fraction in [0, 1]).
  Normaliser widened_to(const Normaliser& reference, double fraction) const;
  // These ranges, each widened symmetrically to at least `fraction` x the largest range of its
  // channel over all vertices (fraction in [0, 1]).
  Normaliser with_channel_floor(double fraction) const;

  // x: raw DR features of shape [..., V, 9] or [..., V * 9] -> the same shape, in [-0.9, 0.9] for
  // training data: 1.8 (x - min) / (max - min) - 0.9. Differentiable; keeps x's dtype and device.
  torch::Tensor normalise(const torch::Tensor& x) const;
  // normalise(x) limited to what the training data spans, for features from elsewhere (an
  // avatar's deformation-transfer results): a dimension that was constant in training (its
  // range widened to kMinimumRange) takes its training value, 0; every other one is clamped to
  // [-0.9, 0.9]. x: [..., V, 9] as normalise.
  torch::Tensor normalise_within_range(const torch::Tensor& x) const;
  // The inverse: y of shape [..., V, 9] or [..., V * 9] -> raw DR features.
  torch::Tensor denormalise(const torch::Tensor& y) const;

  // A tensor file (core/tensor_io.h) holding `min` and `max` ([V, 9] float32) and `bound` (0.9).
  void save(const std::string& path) const;
  // Throws retarget::Error naming the file for missing tensors, bad shapes or min > max.
  static Normaliser load(const std::string& path);
};

}  // namespace retarget
