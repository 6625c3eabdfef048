// Checkpoint files of the trainers: a module's parameters, optionally the optimiser's state, and
// where the run stood (epochs done, the best epoch). LibTorch's own archive format, written
// atomically. The VAE trainer (train/vae_run.h) and the translation trainer use it.
#pragma once

#include <torch/torch.h>

#include <string>
#include <utility>
#include <vector>

namespace retarget {

// Training state of a checkpoint besides the weights.
struct CheckpointState {
  int epoch = 0;               // epochs completed
  int best_epoch = -1;         // 1-based, -1: none yet
  double best_validation = 0;  // its validation loss
};

// Writes the module's parameters (no buffers: they are rebuilt with the module), the optimiser's
// state if given, and `state`, atomically. Throws retarget::Error naming the file.
void save_checkpoint(const std::string& path, const torch::nn::Module& module, torch::optim::Optimizer* optimizer,
                     const CheckpointState& state);

// Reads a checkpoint into `module` (and `optimizer` if given). `what` names the model in
// messages ("VAE", "translation"). Throws retarget::Error naming the file for a missing file,
// another architecture (a parameter missing or of another shape), or a checkpoint without
// optimiser state when one is asked for.
CheckpointState load_checkpoint(const std::string& path, torch::nn::Module& module, torch::optim::Optimizer* optimizer,
                                const std::string& what);

// The state alone (no module needed). Throws retarget::Error naming the file for a missing or
// unreadable file, or a state field that is not one finite number (whole, for the epochs).
CheckpointState read_checkpoint_state(const std::string& path);

// Trainers with several optimisers (the CycleGAN baseline's generators and discriminators): each
// stored under its name. The single-optimiser functions above store theirs as "optimiser".
using NamedOptimizers = std::vector<std::pair<std::string, torch::optim::Optimizer*>>;
void save_checkpoint(const std::string& path, const torch::nn::Module& module, const NamedOptimizers& optimizers,
                     const CheckpointState& state);
CheckpointState load_checkpoint(const std::string& path, torch::nn::Module& module, const NamedOptimizers& optimizers,
                                const std::string& what);

}  // namespace retarget
