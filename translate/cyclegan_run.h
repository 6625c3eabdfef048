// A finished (or running) CycleGAN+LFD run read back (translate/cyclegan_trainer.h): every
// network with the weights of checkpoints/last.pt, and the retargeting bundle of its generator
// from human to avatar codes between the run's two VAEs (`retarget export RUN`).
#pragma once

#include <string>

#include "export/bundle_export.h"
#include "models/latent_cyclegan.h"
#include "train/checkpoint.h"
#include "translate/cyclegan_config.h"

namespace retarget {

struct TrainedCycleGan {
  std::string folder;
  CycleGanTrainConfig config;
  LatentCycleGan net{nullptr};  // eval mode
  CheckpointState state;        // state.epoch: CycleGAN epochs the weights had trained
};

// Throws retarget::Error for a folder that is not a CycleGAN run, a missing checkpoint, or VAE
// runs whose latent sizes no longer fit.
TrainedCycleGan load_trained_cyclegan(const std::string& folder);

// The human VAE's encoder, the generator G, the avatar VAE's decoder and rig; throws
// retarget::Error when a VAE run no longer loads or its dataset's topology changed since.
BundleParts cyclegan_bundle_parts(const TrainedCycleGan& trained);

}  // namespace retarget
