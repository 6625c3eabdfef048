// The constants of the project's one normalisation of DR features (data/normaliser.h): every
// (vertex, channel) is mapped min-max to [-kNormalisedBound, kNormalisedBound] with ranges from
// the training split,
//   normalise(x) = 2 * kNormalisedBound * (x - min) / (max - min) - kNormalisedBound,
// and the decoders end in tanh. Here so that models/ (TorchScript export) and train/ share them.
#pragma once

namespace retarget {

constexpr double kNormalisedBound = 0.9;  // training data maps into [-0.9, 0.9]
constexpr double kMinimumRange = 1e-5;    // narrower ranges (constant dimensions) are widened to this

}  // namespace retarget
