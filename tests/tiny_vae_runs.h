// Tiny VAE runs for the tests of what is trained on top of them (the translation network, the
// CycleGAN baseline): a small config and a quiet training.
#pragma once

#include <string>

#include "core/config.h"
#include "train/vae_config.h"
#include "train/vae_trainer.h"

namespace retarget::test {

// A VAE config on `dataset` into `output`: 3 epochs, channels [9, 8, 4, 1], the given latent size
// and seed, one thread.
inline std::string tiny_vae_config(const std::string& dataset, const std::string& output, int latent, int seed) {
  return "task: vae\n"
         "data: {dataset: " +
         dataset +
         ", validation_fraction: 0.2}\n"
         "model: {channels: [9, 8, 4, 1], hidden: 32, latent: " +
         std::to_string(latent) +
         ", order: 2}\n"
         "loss: {kl_weight: 1.0e-4}\n"
         "optimiser: {lr: 1.0e-2}\n"
         "training: {epochs: 3, batch_size: 4, checkpoint_every: 1, seed: " +
         std::to_string(seed) +
         ", threads: 1}\n"
         "output: " +
         output + "\n";
}

// Trains the config without a progress bar.
inline void train_tiny_vae(const std::string& config_text) {
  VaeTrainOptions o;
  o.progress = nullptr;
  train_vae(read_vae_train_config(ConfigNode::parse(config_text, "vae.yaml")), o);
}

}  // namespace retarget::test
