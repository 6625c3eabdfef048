// The YAML config of the CycleGAN+LFD baseline (`retarget train <config.yaml>` with `task:
// cyclegan`; the paper's section 6.3.1 after its reference [44]): a latent CycleGAN between the
// human VAE's and the avatar VAE's codes, trained without any correspondence or comparison, the
// light-field distance (render/light_field.h) standing in for "looks alike". Its generator from
// human to avatar codes is F's network (models/translation_mlp.h), so its bundle runs wherever
// F's does. configs/train/cyclegan.yaml is a commented example.
//
//   task: cyclegan
//   data:
//     human_vae: out/demo/runs/human_vae      # a human VAE run folder (train/vae_run.h)
//     human_checkpoint: best                  # best | last
//     avatar_vae: out/demo/runs/avatar_vae    # an avatar VAE run folder
//     avatar_checkpoint: best                 # best | last
//   light_field: {samples: 300, size: 64, zernike_order: 10, fourier: 10}
//   model: {hidden: 100, negative_slope: 0.1, critic_hidden: 64}
//   similarity: {epochs: 300, lr: 1.0e-3, batch_size: 256}
//   loss: {adversarial: 1, cycle: 10, similarity: 1}
//   optimiser: {lr: 2.0e-4}
//   training: {epochs: 200, batch_size: 64, checkpoint_every: 10, seed: 1, threads: 0}
//   output: out/runs/fox-cyclegan
//
// light_field.samples: training samples per side (drawn with the seed) whose light fields are
// computed; the similarity regressor learns the normalised distances of all their pairs. The
// rest of light_field is render/light_field.h's options. Relative paths are relative to the
// working directory; every key is checked, an unknown one fails with its key path.
#pragma once

#include <string>

#include "core/config.h"
#include "models/translation_mlp.h"
#include "render/light_field.h"
#include "train/train_config.h"

namespace retarget {

struct CycleGanDataOptions {
  std::string human_vae, human_checkpoint = "best";    // human VAE run folder (required)
  std::string avatar_vae, avatar_checkpoint = "best";  // avatar VAE run folder (required)
  void validate(const std::string& key_path = "data") const;
};

// The light-field similarity regressor S(x, y) -> normalised LFD in [0, 1], fitted before the
// CycleGAN on every pair of the sampled human and avatar samples (10% of the pairs held out to
// report how well it fits). Adam at lr, epochs passes over the pairs in batches.
struct SimilarityOptions {
  int samples = 300;  // per side, >= 2 (light_field.samples)
  int epochs = 300;
  double lr = 1e-3;
  int batch_size = 256;
  void validate(const std::string& key_path = "similarity") const;
};

// L_G = adversarial (LSGAN, both directions) + cycle (mean |F(G(x)) - x| + |G(F(y)) - y|) +
// similarity (mean S(x, G(x)) + S(F(y), y)); each weight >= 0.
struct CycleGanLossWeights {
  double adversarial = 1, cycle = 10, similarity = 1;
  void validate(const std::string& key_path = "loss") const;
};

struct CycleGanTrainingOptions : TrainingLoopOptions {
  CycleGanTrainingOptions() {
    batch_size = 64;
    checkpoint_every = 10;
  }
  int epochs = 200;  // passes over the larger of the two code sets
};

struct CycleGanTrainConfig {
  std::string source;  // the config file (for messages)
  CycleGanDataOptions data;
  LightFieldOptions light_field;
  SimilarityOptions similarity;
  TranslationMlpOptions model;  // both generators' hidden width and slope (latent sizes from the VAEs)
  int critic_hidden = 64;       // the discriminators' and the regressor's hidden width, > 0
  CycleGanLossWeights loss;
  double lr = 2e-4;  // Adam for generators and discriminators, > 0
  CycleGanTrainingOptions training;
  std::string output;  // the run folder (required)
  void validate() const;
};

// Reads a `task: cyclegan` document. Throws retarget::Error naming file, line and key path.
CycleGanTrainConfig read_cyclegan_train_config(const ConfigNode& root);

// The config as YAML with every key written out (the run folder's config.yaml).
std::string to_yaml(const CycleGanTrainConfig& config);

}  // namespace retarget
