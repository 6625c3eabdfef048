// The YAML config of a VAE training run (`retarget train <config.yaml>` with `task: vae`).
// Defaults are the paper's (method notes): Adam 1e-4, decayed by 0.6 every 10 epochs, batch
// 30, 100 epochs, latent 25. configs/train/*.yaml are commented profiles.
//
//   task: vae
//   data:
//     dataset: out/demo/fox-dataset   # a folder written by `retarget dataset` (data/dataset.h)
//     validation_fraction: 0.1        # of the training split, for choosing the best checkpoint
//     target_normaliser: targets      # human datasets: decode in the targets' own ranges (or shared)
//   model:    {channels: [9, 128, 64, 64, 64, 1], hidden: 300, latent: 25, order: 2,   # or latent: auto
//              decoder_start: random,   # or principal (train/principal_decoder.h)
//              encoder_skip: false}     # or true: a linear input -> code path (models/mesh_vae.h)
//   loss:     {kl_weight: 1.0e-5, reconstruction: l1}   # or squared (models/losses.h)
//   optimiser: {lr: 1.0e-4, betas: [0.9, 0.999], weight_decay: 0}
//   schedule: {decay: 0.6, every: 10}  # lr = lr0 * decay ^ floor(epoch / every)
//   training: {epochs: 100, batch_size: 30, checkpoint_every: 1, seed: 1, threads: 0}
//   output: out/runs/fox-vae         # the run folder (`retarget train --out`)
//
// The profiles under configs/train name neither data.dataset nor output: `retarget train` takes
// them from --set and --out (a missing one is an error saying so); a profile may name a `base:`
// it is merged over (core/config_base.h).
// Relative paths (but `base:`'s) are relative to the working directory. Every key is checked:
// an unknown key fails with its key path and the closest known key, before any work.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "models/losses.h"
#include "models/mesh_vae.h"
#include "train/train_config.h"

namespace retarget {

struct VaeDataOptions {
  std::string dataset;               // dataset folder (required)
  std::string dataset_where;         // where `dataset` was given ("file:line: data.dataset"), for messages
  double validation_fraction = 0.1;  // of the training split (avatars: samples; humans: subjects); [0, 1)
  // Human datasets: the ranges the decoder's outputs are normalised in. "targets": the
  // identity-averaged targets' own (Dataset::target_normaliser); "shared": the one normaliser of
  // inputs and targets (runs made before the option; a run folder whose config.yaml lacks the
  // key is read as "shared"). Avatars decode what they encode: both are the same there.
  std::string target_normaliser = "targets";
  void validate(const std::string& key_path = "data") const;
};

struct OptimiserOptions {
  double lr = 1e-4;
  double beta1 = 0.9, beta2 = 0.999;  // `betas: [b1, b2]`
  double weight_decay = 0;
  void validate(const std::string& key_path = "optimiser") const;
};

// Step decay: lr(epoch) = lr * decay ^ floor(epoch / every), epochs counted from 0.
struct ScheduleOptions {
  double decay = 0.6;  // (0, 1]
  int every = 10;      // epochs, > 0
  void validate(const std::string& key_path = "schedule") const;
  double lr_at(double lr, int epoch) const;
};

struct TrainingOptions : TrainingLoopOptions {
  int epochs = 100;
  TrainingOptions() { batch_size = 30; }
  void validate(const std::string& key_path = "training") const;
};

// How the decoder's weights start: LibTorch's random initialisation (the paper's), or at the
// training targets' principal components (train/principal_decoder.h).
enum class DecoderStart { random, principal };

struct VaeTrainConfig {
  std::string source;  // the config file (for messages)
  VaeDataOptions data;
  MeshVaeOptions model{1};                            // vertices are set from the dataset; the rest from `model:`
  DecoderStart decoder_start = DecoderStart::random;  // `model.decoder_start`
  double kl_weight = 1e-5;                            // `loss.kl_weight`
  // `loss.reconstruction`: l1 (the method notes') or squared; see ReconstructionLoss.
  ReconstructionLoss reconstruction = ReconstructionLoss::l1;
  OptimiserOptions optimiser;
  ScheduleOptions schedule;
  TrainingOptions training;
  std::string output;  // the run folder (required)
  void validate() const;
};

// `model.latent: auto`: the paper's 25, or the avatar dataset's controller count where that is
// larger. A rig's expressions span about as many directions as it has controllers, nearly
// linearly; on the ICT head as a 53-controller rig the first 25 principal components of its
// features reconstruct them to x0.50 of the neutral answer's L1, the first 53 to x0.14. Resolved
// when the config is read (from the dataset's manifest alone) and written into the run's
// config.yaml as the number it became.
constexpr int64_t kPaperLatent = 25;
// The latent `auto` gives for `dataset` (data.dataset); fails at `where` when the folder's
// manifest cannot be read.
int64_t automatic_latent(const std::string& dataset, const ConfigNode& where);

// Reads a `task: vae` document (config_task and the file with overrides: train/train_config.h). Throws retarget::Error
// naming file, line and key path.
VaeTrainConfig read_vae_train_config(const ConfigNode& root);

// The config as YAML, every key written out (defaults too): the run folder keeps this copy,
// so a run can be reproduced and resumed from its own folder.
std::string to_yaml(const VaeTrainConfig& config);

}  // namespace retarget
