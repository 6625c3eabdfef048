// Training of a mesh VAE from a `task: vae` config (train/vae_config.h) into a run folder
// (train/run_folder.h).
//
// What it trains follows from the dataset: on an avatar dataset the VAE reconstructs its
// input; on a human dataset it maps each person's expression to the identity-averaged shape
// of that expression (the human expression VAE of the method notes). Inputs and targets are
// normalised with the dataset's normaliser. The validation set is a seeded share of the
// training split (avatars: samples; humans: subjects); the best checkpoint is the epoch with
// the lowest validation L1 (codes = means, no sampling), or the training loss without one.
//
// Reproducible: the seed fixes the initial weights, each epoch's batch order and its sampling
// noise (re-seeded per epoch from the seed and the epoch), so a run resumed from a checkpoint
// ends with the same weights as one that was never interrupted (with one thread; several
// threads may sum in another order).
#pragma once

#include <iostream>
#include <string>

#include "train/run_folder.h"
#include "train/vae_config.h"

namespace retarget {

struct VaeTrainOptions {
  RunStart start = RunStart::fresh;
  std::ostream* progress = &std::cerr;  // per-epoch progress bars (nullptr: none)
  // Stop as if interrupted after this many epochs in this process (tests); -1: run to the end.
  int stop_after_epochs = -1;
};

struct VaeTrainSummary {
  std::string folder;
  bool finished = false;
  int epochs_done = 0, epochs_run = 0;  // in the run / in this process
  int best_epoch = -1;
  double best_validation = 0;
  double last_train_loss = 0;   // total loss of the last epoch
  double first_train_loss = 0;  // of the first epoch run in this process
  int64_t train_samples = 0, validation_samples = 0;
  double seconds = 0;
  double samples_per_second = 0;  // training samples per second of training
};

// Trains as configured. With RunStart::resume the run's own config.yaml is used and `config`
// only names the folder (config.output). Throws retarget::Error for a bad dataset or folder.
VaeTrainSummary train_vae(const VaeTrainConfig& config, const VaeTrainOptions& options = {});

}  // namespace retarget
