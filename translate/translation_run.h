// A finished (or running) translation run read back: F with the weights of one checkpoint, and
// the retargeting bundle made from it with the two VAE runs it was trained between
// (export/bundle_export.h): the human VAE's encoder (data.human_vae, data.human_checkpoint),
// F, and the avatar VAE's decoder (the correspondences' run and checkpoint).
#pragma once

#include <string>

#include "export/bundle_export.h"
#include "models/translation_mlp.h"
#include "train/checkpoint.h"
#include "train/vae_run.h"
#include "translate/translation_config.h"

namespace retarget {

struct TrainedTranslation {
  std::string folder;
  TranslationTrainConfig config;
  TranslationMlp translation{nullptr};  // eval mode
  CheckpointState state;                // state.epoch: epochs the weights had trained
  std::string checkpoint;               // the file read
};

// which: "last" or "stage<N>" (N = 1 .. the number of stages; checkpoints/stage<N>.pt holds F
// after stage N). Throws retarget::Error for a folder that is not a translation run, an unknown
// or missing checkpoint, or VAE runs whose latent sizes no longer fit F.
TrainedTranslation load_trained_translation(const std::string& folder, const std::string& which = "last");

// The bundle's parts: the human side from the run's human VAE (encoder, its dataset's
// normaliser, rest mesh, DR options, name, units), F, the avatar side from the correspondences'
// avatar VAE run (decoder, ...), and the avatar dataset's rig (load_rig of its source, with the
// millimetres per unit of its eye landmarks, 0 without them) for retarget-infer --weights. Throws
// retarget::Error when a run or the correspondences no longer load, or a dataset's topology
// changed since the translation run was trained. A rig that does not load or no longer has the
// dataset's topology leaves parts.rig empty, with a warning (the bundle then has no rig).
BundleParts translation_bundle_parts(const TrainedTranslation& trained);

// The bundle of any code-to-code network between two VAE runs (F, LEC, the CycleGAN's
// generator): the human side from `human`, `translation`, the avatar side and rig from `avatar`.
BundleParts bundle_parts_between(const TrainedVae& human, const TranslationMlp& translation, const TrainedVae& avatar);

}  // namespace retarget
