// Linear expression cloning (LEC; the paper's section 6.2.3, eq. 9, after its reference [6]):
// the linear version of the translation network F, a baseline beside it. One matrix and offset
// take a human code to an avatar code, fitted by least squares to the pairs F's paired loss
// learns from: every training input's human code x (TranslationData::inputs) and its
// expression's avatar code y0 (the correspondences' start, which the rounds of comparisons chose:
// the belief's bet, or a round's champion).
//
// So that LEC runs wherever F does (retarget-infer, streams, takes), it is built as F's own
// network (models/translation_mlp.h) with LeakyReLU slope 1 (the identity), f1 the identity and
// f2, f3 zero: g computes M x + b, and `retarget export RUN --lec` writes it as a bundle.
#pragma once

#include <torch/torch.h>

#include "models/translation_mlp.h"

namespace retarget {

struct LecOptions {
  // Ridge on M, as a fraction of the inputs' mean variance (0: plain least squares, which the
  // paper's eq. 9 is; a little keeps near-collinear pairs from collapsing the map, the failure
  // the paper shows for Conan).
  double ridge = 1e-4;
  void validate() const;  // throws retarget::Error naming "lec.ridge"
};

// inputs [N, Lh] and targets [N, La] float32, N >= 1. Returns F's network computing
// z -> M z + b for the least-squares M [La, Lh] and b [La] (eval mode). Throws retarget::Error
// for mismatched or empty tensors.
TranslationMlp fit_linear_expression_cloning(const torch::Tensor& inputs, const torch::Tensor& targets,
                                             const LecOptions& options = {});

}  // namespace retarget
