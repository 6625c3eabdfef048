// The codes the translation network F is trained on (paper, sections 5.1-5.2), read from a
// translation config's runs and folders:
//   x       human codes: the human VAE's encoder means (eval mode, no sampling) of the
//           training subjects' samples or of the identity-averaged targets (data.human_codes)
//   y0      [K, La] the deformation-transfer codes of the correspondences
//   groups  [K, P, La] the codes of each expression's retrieved avatar samples
//   triplets (k, positive code, negative code) from the annotation project, each positive and
//           negative looked up in group k; split into training and held-out triplets (seeded)
// and checks that they belong together: the human VAE's dataset and the avatar VAE's dataset are
// the correspondences' (check_correspondences), and the avatar VAE is the one that made y0 (its
// encoder reproduces y0 from the stored DT features), so codes from another avatar run, or a run
// retrained after the correspondences were built, are refused.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <string>
#include <vector>

#include "annotate/annotation_store.h"
#include "correspond/correspondence.h"
#include "train/vae_run.h"
#include "translate/translation_config.h"

namespace retarget {

// Triplets over the inputs: one row per (triplet, input of its expression), the rows of
// triplet t being offsets[t] .. offsets[t + 1] - 1.
struct TripletCodes {
  torch::Tensor anchor;          // [R] int64, row of TranslationData::inputs
  torch::Tensor positive;        // [R, La] float32, group_codes[k][p] of the positive sample
  torch::Tensor negative;        // [R, La] float32
  torch::Tensor group_scale;     // [R] float32, 1 / group_spread of the row's group
  int64_t triplets = 0;          // annotated triplets behind the rows
  std::vector<int64_t> offsets;  // [triplets + 1]
  int64_t rows() const { return anchor.defined() ? anchor.size(0) : 0; }
};

// The smallest group spread (squared code units): a group of identical codes would give its
// triplets an infinite scale.
constexpr double kMinGroupSpread = 1e-10;

struct TranslationData {
  std::vector<std::string> expressions;  // K, the correspondences' order
  torch::Tensor inputs;                  // [N, Lh] float32 human codes x
  torch::Tensor input_expression;        // [N] int64 in [0, K)
  // Codes of the human dataset's TEST subjects for the same expressions (to see how F does on
  // people it never saw); [M, Lh] and [M], M may be 0.
  torch::Tensor test_inputs, test_expression;
  torch::Tensor y0;           // [K, La] float32
  torch::Tensor group_codes;  // [K, P, La] float32
  // [K] float32: the mean squared distance of group k's codes from their centroid (floored at
  // kMinGroupSpread), the unit of the triplet loss under `loss.triplet_scale: group`.
  torch::Tensor group_spread;
  TripletCodes train_triplets, held_out_triplets;
  int64_t triplets_loaded = 0;                        // from data.triplets, before the split
  std::string human_fingerprint, avatar_fingerprint;  // of the two datasets (for run.yaml)

  int64_t latent_in() const { return inputs.size(1); }
  int64_t latent_out() const { return y0.size(1); }
};

// Everything above from config.data. Throws retarget::Error for a missing or mismatched run,
// dataset, correspondence folder or annotation project, an expression of the correspondences
// the human dataset lacks, and a triplet whose anchor is no expression of the correspondences or
// whose sample is not in its group (naming the triplet).
TranslationData load_translation_data(const TranslationDataOptions& data, uint64_t seed);

// The same from runs already loaded (tests, evaluation): `human` a human VAE run, `avatar` the
// avatar VAE run of `correspondences`, `triplets` as AnnotationStore::triplets gives them;
// `triplets_source` names them in messages. `faces`: the human dataset F learns from
// (TranslationDataOptions::human_dataset), coded by `human`'s encoder and normaliser; null: the
// VAE's own. Throws retarget::Error naming it when it is not a human dataset of the VAE's topology.
TranslationData make_translation_data(TrainedVae& human, TrainedVae& avatar, const Correspondences& correspondences,
                                      const std::vector<Triplet>& triplets, const std::string& triplets_source,
                                      HumanCodes codes, double held_out_fraction, uint64_t seed,
                                      const Dataset* faces = nullptr);

}  // namespace retarget
