// Training of the CycleGAN+LFD baseline (models/latent_cyclegan.h) from a `task: cyclegan`
// config (translate/cyclegan_config.h) into a run folder (train/run_folder.h):
//
// 1. The light-field similarity: the normalised light-field distances of the sampled pairs
//    (translate/cyclegan_data.h) are fitted by the regressor S (MSE through a sigmoid, Adam,
//    similarity.epochs passes over 90% of the pairs; the other 10% report how well it fits,
//    beside predicting their mean). Written to RUN/similarity.yaml; S is then held fixed.
// 2. The CycleGAN on the codes of both training sets, unpaired: each step draws a batch of human
//    codes x and one of avatar codes y and
//      - updates the discriminators:  0.5 [(D_a(y) - 1)^2 + D_a(G(x))^2] + the same for D_h
//        (least-squares GAN, as CycleGAN), translated codes detached;
//      - updates the generators:      adversarial [(D_a(G(x)) - 1)^2 + (D_h(G'(y)) - 1)^2]
//                                   + cycle [|G'(G(x)) - x| + |G(G'(y)) - y|] (mean per dimension)
//                                   + similarity [S(x, G(x)) + S(G'(y), y)].
//    One epoch is max(Nh, Na) / batch_size steps; batches of the smaller set wrap around.
//
// Logged per epoch (metrics.jsonl / .csv), over the whole code sets after the epoch: epoch,
// generator (the weighted L_G), adversarial, cycle (cycle_human + cycle_avatar), cycle_human,
// cycle_avatar, similarity (mean predicted distance of x to G(x) and of G'(y) to y),
// discriminator, seconds. The cycle loss falls as the two generators learn to invert each other.
//
// Checkpoints: checkpoints/last.pt (every network, both Adam states, the epoch) after the
// similarity fit (epoch 0), every checkpoint_every epochs and at the end. A run resumed from it
// ends as one never interrupted (batches seeded from the seed and the epoch; one thread); one
// killed before its first checkpoint starts again.
#pragma once

#include <iostream>
#include <string>

#include "train/run_folder.h"
#include "translate/cyclegan_config.h"

namespace retarget {

struct CycleGanTrainOptions {
  RunStart start = RunStart::fresh;
  std::ostream* progress = &std::cerr;  // progress bars (nullptr: none)
  int stop_after_epochs = -1;           // stop as if interrupted after this many epochs here (tests)
};

struct CycleGanEpochMetrics {
  int epoch = 0;  // 1-based
  double generator = 0, adversarial = 0, cycle = 0, cycle_human = 0, cycle_avatar = 0, similarity = 0,
         discriminator = 0;
};

// How well S fits the light-field distances: mean squared errors in normalised distance units.
struct SimilarityFit {
  int64_t pairs = 0, held_out_pairs = 0;
  double train_mse = 0, held_out_mse = 0;
  double held_out_mean_mse = 0;  // predicting the training pairs' mean distance for every held-out pair
};

struct CycleGanTrainSummary {
  std::string folder;
  bool finished = false;
  int epochs_done = 0, epochs_run = 0;
  int64_t human_codes = 0, avatar_codes = 0;
  SimilarityFit fit;                 // read back from RUN/similarity.yaml when resumed
  CycleGanEpochMetrics first, last;  // first and last epoch run in this process
  double seconds = 0;
};

// Trains as configured. With RunStart::resume the run's own config.yaml is used. Throws
// retarget::Error for bad runs or folders, and when a loss stops being finite.
CycleGanTrainSummary train_cyclegan(const CycleGanTrainConfig& config, const CycleGanTrainOptions& options = {});

}  // namespace retarget
