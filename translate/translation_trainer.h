// Training of the translation network F (models/translation_mlp.h) from a `task: translation`
// config (translate/translation_config.h) into a run folder (train/run_folder.h), in the paper's
// progressive stages (section 5.3): each stage minimises
//   L_total = aP L_P + aG L_G + aT L_T          (models/losses.h, squared code distances)
// with its own weights and learning rate, on the codes of translate/translation_data.h.
//
// One epoch is one pass over the human inputs in shuffled batches of training.batch_size; the
// training triplets are shuffled too and spread evenly over the epoch's steps, each anchored on
// one input of its expression drawn for the epoch (with human_codes: subjects, a random training
// subject's code; over the epochs every subject serves), so every epoch sees every input and
// every triplet once (anchoring every triplet on every subject in every epoch made an epoch ~10x
// slower on the synthetic default, 19 training subjects). The logged accuracies and L_T are over
// all (triplet, input) pairs.
//
// Stages: each stage starts a NEW Adam optimiser (moments and step count reset) at the stage's
// learning rate. Keeping the moments would carry the last stage's gradient scale into a loss
// whose scale just changed (aG 1e-4 -> 1, aT 1e-4 -> 10): Adam's first steps would be sized by
// stale second moments. Within a stage the learning rate is constant.
//
// Logged per epoch (metrics.jsonl / .csv), all evaluated on the whole training set after the
// epoch with the weights it ends with: epoch, stage (1-based), lr, weight_paired, weight_group,
// weight_triplet, loss (the weighted total of this stage), paired, group, triplet (unweighted
// L_P, L_G, L_T), train_accuracy and held_out_accuracy (fraction of triplets with D(a, p) <
// D(a, n); empty without triplets), held_out_triplet (L_T of the held-out triplets),
// test_paired (L_P of the human test subjects' codes: how F does on people it never saw),
// seconds.
//
// Checkpoints: checkpoints/last.pt (weights, Adam state, epoch) every checkpoint_every epochs and
// at the end of every stage; checkpoints/stage<N>.pt (weights) when stage N ends, so that F after
// stage 1 only can be exported and compared with the full schedule (a 0-epoch stage's snapshot
// holds the weights the stage before it ended with). A run resumed from last.pt, mid-stage or
// not, ends with the same weights as one never interrupted (batch and triplet orders are seeded
// from the seed and the epoch; one thread).
#pragma once

#include <iostream>
#include <string>
#include <vector>

#include "train/data_parallel.h"
#include "train/run_folder.h"
#include "translate/translation_config.h"

namespace retarget {

struct TranslationTrainOptions {
  RunStart start = RunStart::fresh;
  std::ostream* progress = &std::cerr;  // one progress bar over all epochs (nullptr: none)
  // Stop as if interrupted after this many epochs in this process (tests); -1: run to the end.
  int stop_after_epochs = -1;
  // Data-parallel (train/data_parallel.h): each rank takes its part of every batch's inputs and
  // triplets, rank 0 writes; null: one process.
  DataParallelPtr parallel;
};

// The metrics of one epoch (as logged).
struct TranslationEpochMetrics {
  int epoch = 0, stage = 0;  // 1-based
  double lr = 0;
  double loss = 0, paired = 0, group = 0, triplet = 0;
  double train_accuracy = 0, held_out_accuracy = 0, held_out_triplet = 0, test_paired = 0;  // NaN: none
};

struct TranslationStageSummary {
  std::string name;
  int epochs = 0;
  TranslationEpochMetrics end;  // metrics of its last epoch (epochs > 0 and reached)
};

struct TranslationTrainSummary {
  std::string folder;
  bool finished = false;
  int epochs_done = 0, epochs_run = 0;  // in the run / in this process
  int64_t inputs = 0, expressions = 0, test_inputs = 0;
  int64_t triplets = 0, train_triplets = 0, held_out_triplets = 0;
  TranslationEpochMetrics first, last;          // first and last epoch run in this process
  std::vector<TranslationStageSummary> stages;  // stages that ended in this process (not 0-epoch ones)
  double seconds = 0;
};

// Trains as configured. With RunStart::resume the run's own config.yaml is used and `config`
// only names the folder (config.output). Throws retarget::Error for bad data or folders, and if
// the loss stops being finite.
TranslationTrainSummary train_translation(const TranslationTrainConfig& config,
                                          const TranslationTrainOptions& options = {});

}  // namespace retarget
