// What the CycleGAN+LFD baseline (translate/cyclegan_trainer.h) trains on, read from its
// config's two VAE runs: no correspondences and no comparisons, only
//   codes        the encoder means (eval mode) of every training sample of the human dataset
//                (training people, every expression) and of the avatar dataset
//   light fields the normalised light-field distance (render/light_field.h) of every pair of a
//                seeded subset of those samples, one human and one avatar: each sample's mesh
//                rebuilt from its DR features (aligned to the rest pose) and described from its
//                ten silhouettes; the L1 distances of the pairs scaled into [0, 1] by their
//                smallest and largest (the paper: "normalize the scores into [0, 1]").
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <iosfwd>
#include <string>

#include "render/light_field.h"
#include "train/vae_run.h"

namespace retarget {

struct CycleGanCodes {
  torch::Tensor human;   // [Nh, Lh] float32
  torch::Tensor avatar;  // [Na, La] float32
};

// Encoder means of each dataset's training split, in d.train's order.
CycleGanCodes training_codes(TrainedVae& human, TrainedVae& avatar);

struct LightFieldPairs {
  torch::Tensor human, avatar;      // [Ph, Lh] and [Pa, La]: the codes of the sampled samples
  torch::Tensor distance;           // [Ph, Pa] float32 in [0, 1]: normalised LFD of each pair
  double raw_min = 0, raw_max = 0;  // the L1 distances that became 0 and 1
};

// `samples` training samples per side (all when fewer), drawn with `seed`; their light fields are
// computed on the machine's cores (progress: a bar, nullptr: none), their codes taken from
// `codes` (training_codes of the same runs). Throws retarget::Error when a dataset has fewer
// than two training samples or every pair lies at the same distance.
LightFieldPairs light_field_pairs(const TrainedVae& human, const TrainedVae& avatar, const CycleGanCodes& codes,
                                  int samples, const LightFieldOptions& options, uint64_t seed, std::ostream* progress);

}  // namespace retarget
