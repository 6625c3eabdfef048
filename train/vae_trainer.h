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
// Honest: before the first epoch the trainer scores the trivial answers on the validation set
// (the training set when there is none) with the validation loss: "neutral" (the rest pose,
// normalise(zeros), for every target) and "mean" (the mean normalised training target). They
// are logged beside every epoch's validation L1, written into each metrics row
// (neutral_validation_l1, mean_validation_l1) and into run.yaml (`baselines`). When the run
// finishes it warns (log and run.yaml `warnings`) if the best validation L1 is not below 0.9 x
// the better trivial answer, or if it stopped improving early (best epoch <= max(2, 25% of the
// planned epochs) with at least 8 epochs run).
//
// Reproducible: the seed fixes the initial weights, each epoch's batch order and its sampling
// noise (re-seeded per epoch from the seed and the epoch), so a run resumed from a checkpoint
// ends with the same weights as one that was never interrupted (with one thread; several
// threads may sum in another order).
#pragma once

#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "train/data_parallel.h"
#include "train/run_folder.h"
#include "train/vae_config.h"

namespace retarget {

struct VaeTrainOptions {
  RunStart start = RunStart::fresh;
  std::ostream* progress = &std::cerr;  // per-epoch progress bars (nullptr: none)
  // Stop as if interrupted after this many epochs in this process (tests); -1: run to the end.
  int stop_after_epochs = -1;
  // Data-parallel (train/data_parallel.h): each rank trains on its shard of every batch, rank 0
  // writes; null: one process.
  DataParallelPtr parallel;
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
  // The trivial answers' validation L1 ("neutral", "mean"; normalised units as
  // best_validation) and the run's warnings (as in run.yaml; empty for a healthy run).
  std::map<std::string, double> baselines;
  std::vector<std::string> warnings;
};

// Trains as configured. With RunStart::resume the run's own config.yaml is used and `config`
// only names the folder (config.output). Throws retarget::Error for a bad dataset or folder.
VaeTrainSummary train_vae(const VaeTrainConfig& config, const VaeTrainOptions& options = {});

// The warnings a finished run gets (see the top): best_validation: the best epoch's loss
// (normalised L1), best_epoch 1-based (0: the principal start, which no epoch beat; -1: none), baselines: trivial
// answer -> the same loss (non-finite values are ignored); loss_name names the loss in the message ("validation L1").
// Empty for a healthy run.
std::vector<std::string> vae_training_warnings(double best_validation, int best_epoch, int epochs_done,
                                               int epochs_planned, const std::map<std::string, double>& baselines,
                                               const std::string& loss_name = "validation L1");

// What the trainer adds (logged, not a warning) when a run trained with `loss` does not beat the
// trivial answer: with L1, to try the squared error (an L1 VAE can settle on the neutral face);
// with the squared error, that its mm figure (`retarget eval vae`) is the one to judge by.
std::string trivial_answer_advice(ReconstructionLoss loss);

}  // namespace retarget
