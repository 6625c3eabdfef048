// The YAML config of a translation run (`retarget train <config.yaml>` with `task: translation`):
// the network F from human expression codes to avatar expression codes, trained on the
// correspondences of one human face set and one avatar (paper, sections 5.1-5.3) in progressive
// stages. Defaults are the paper's; configs/train/translation.yaml is a commented example.
//
//   task: translation
//   data:
//     human_vae: out/demo/runs/human_vae       # a human VAE run folder (train/vae_run.h)
//     human_checkpoint: best                   # its checkpoint: best | last
//     avatar_vae: out/demo/runs/avatar_vae     # the avatar VAE run the correspondences were built with
//     correspondences: out/demo/corr-fox       # a folder written by build_correspondences
//     triplets: out/demo/annotation-fox        # annotation project folder or .db; empty: none
//     include_derived: true                    # also the triplets inferred by transitivity
//     held_out_fraction: 0.2                   # of the triplets, for held-out accuracy; [0, 1)
//     human_codes: subjects                    # subjects | targets (below)
//   model: {hidden: 100, negative_slope: 0.1}  # latent sizes come from the two VAEs
//   loss: {margin: 0.2, triplet_scale: group}  # triplet margin and the unit of its distances (below)
//   training: {batch_size: 32, checkpoint_every: 10, seed: 1, threads: 0, input_noise: 0}
//   stages:                                    # run in order; a stage with 0 epochs is skipped
//     - {name: paired,  epochs: 500, lr: 1.0e-4, weights: {paired: 1, group: 1.0e-4, triplet: 1.0e-4}}
//     - {name: group,   epochs: 500, lr: 1.0e-5, weights: {paired: 1, group: 1, triplet: 1.0e-4}}
//     - {name: triplet, epochs: 500, lr: 1.0e-6, weights: {paired: 1, group: 1, triplet: 10}}
//   output: out/runs/fox-translation          # the run folder (`retarget train --out`)
//
// The profiles under configs/train name none of data's run folders, the triplets or output:
// `retarget train` takes them from --set and --out (a missing one is an error saying so); a
// profile may name a `base:` it is merged over (core/config_base.h).
//
// human_codes: which human codes x stand for reference expression k.
//   subjects: the encoder means of every TRAINING subject's sample of expression k (the human
//             dataset's training split), each an input with the targets of group k. More inputs,
//             and F sees how codes of real people scatter around the identity-free code, which
//             generalises better to people it has never seen.
//   targets:  one input per k, the encoder mean of the identity-averaged target features of
//             expression k, as the paper (46 reference codes x_k).
// Triplets are anchored on the same inputs: a triplet of expression k counts once per input of k.
//
// triplet_scale: the unit of the triplet loss's squared distances D(a, y) (models/losses.h).
//   group:    the spread of the triplet's group: the mean squared distance of its P codes from
//             their centroid, so the margin is a share of how far apart the candidates are and
//             L_T means the same in every group and for every avatar VAE.
//   absolute: squared code units, as the paper writes eq. 7. The margin 0.2 then presumes a code
//             space in which the candidates of a group lie about that far apart; when they lie
//             much closer (the synthetic fox's groups: 4e-4), no triplet ever clears the margin,
//             every one stays active and L_T only pushes F(x) in one fixed direction per group.
//
// Relative paths (but `base:`'s) are relative to the working directory. Every key is checked:
// an unknown key fails with its key path and the closest known key, before any work.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "models/translation_mlp.h"
#include "train/train_config.h"

namespace retarget {

enum class HumanCodes { subjects, targets };
const char* to_string(HumanCodes codes);

enum class TripletScale { group, absolute };
const char* to_string(TripletScale scale);

struct TranslationDataOptions {
  std::string human_vae;                  // human VAE run folder (required)
  std::string human_checkpoint = "best";  // "best" or "last"
  std::string avatar_vae;                 // avatar VAE run folder (required; the correspondences' run)
  std::string correspondences;            // correspondence folder (required)
  // The human faces F learns from, coded by the human VAE's encoder and normaliser: a dataset of
  // the same face model and topology as the VAE's own (e.g. `retarget dataset --blends N`, random
  // blends beside the recipes), the one the correspondences were built on. Empty: the VAE's own.
  std::string human_dataset;
  std::string triplets;            // annotation project folder or .db file; empty: no triplets
  bool include_derived = true;     // use triplets derived by transitivity too
  double held_out_fraction = 0.2;  // of the triplets (seeded), never trained on; [0, 1)
  HumanCodes human_codes = HumanCodes::subjects;
  void validate(const std::string& key_path = "data") const;
};

// alpha_P, alpha_G, alpha_T of L_total = aP L_P + aG L_G + aT L_T (paper, eq. 8); each >= 0.
struct LossWeights {
  double paired = 1, group = 1e-4, triplet = 1e-4;
  void validate(const std::string& key_path = "weights") const;
};

struct StageOptions {
  std::string name;  // for logs; default "stage<N>"
  int epochs = 0;    // >= 0; 0 skips the stage
  double lr = 1e-4;  // Adam learning rate, > 0
  LossWeights weights;
  void validate(const std::string& key_path = "stages[0]") const;
};

// The paper's progressive schedule (section 5.3, 6.1) with `epochs` epochs per stage (the paper
// does not give epoch counts): stage 1 aP 1, aG = aT = 1e-4, lr 1e-4; stage 2 aG 1, lr 1e-5;
// stage 3 aT 10, lr 1e-6.
std::vector<StageOptions> paper_stages(int epochs = 500);

// batch_size: inputs per step (triplets are spread evenly over the steps); checkpoint_every:
// the end of each stage always writes one too; seed: also the triplet split.
// input_noise (beyond the paper): every step adds to each input code Gaussian noise of this
// many times the training codes' spread about their expression's mean (per code dimension, the
// root mean square over the inputs of x - mean of x's expression; human_codes: subjects only,
// where one expression has many codes), so that F maps the whole cloud of an expression's codes,
// not only the training people's points, to its avatar code: unseen people's codes fall between
// and around them. 0 (the paper) adds none; finite, >= 0.
struct TranslationTrainingOptions : TrainingLoopOptions {
  TranslationTrainingOptions() { checkpoint_every = 10; }
  double input_noise = 0;
};

struct TranslationTrainConfig {
  std::string source;  // the config file (for messages)
  TranslationDataOptions data;
  TranslationMlpOptions model;  // latent_in / latent_out are set from the VAEs; the rest from `model:`
  double margin = 0.2;          // `loss.margin`, >= 0
  TripletScale triplet_scale = TripletScale::group;  // `loss.triplet_scale`
  TranslationTrainingOptions training;
  std::vector<StageOptions> stages = paper_stages();  // at least one, at least one epoch in all
  std::string output;                                 // the run folder (required)
  void validate() const;

  int total_epochs() const;
  // The stage (0-based index into `stages`) that 0-based `epoch` belongs to; stages with 0
  // epochs are never returned. epoch must be in [0, total_epochs()).
  int stage_of(int epoch) const;
  // Epochs done when stage s ends (cumulative, so stage_end(s) - stages[s].epochs is its start).
  int stage_end(int stage) const;
};

// Reads a `task: translation` document. Throws retarget::Error naming file, line and key path.
TranslationTrainConfig read_translation_train_config(const ConfigNode& root);

// The config as YAML with every key written out (the run folder's config.yaml).
std::string to_yaml(const TranslationTrainConfig& config);

}  // namespace retarget
