// Options of a VAE training run in the tests: no progress bar, optionally stopped after a few
// epochs (to resume later).
#pragma once

#include "train/run_folder.h"
#include "train/vae_trainer.h"

namespace retarget::test {

inline VaeTrainOptions quiet(RunStart start = RunStart::fresh, int stop_after = -1) {
  VaeTrainOptions o;
  o.start = start;
  o.progress = nullptr;
  o.stop_after_epochs = stop_after;
  return o;
}

}  // namespace retarget::test
