// A mesh VAE together with what it was trained on: building the model for a dataset's rest
// mesh, its checkpoint files, and reading a finished (or running) run folder back for
// evaluation and export.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <string>

#include "data/dataset.h"
#include "export/vae_export.h"
#include "geometry/mesh.h"
#include "models/mesh_vae.h"
#include "train/checkpoint.h"
#include "train/vae_config.h"

namespace retarget {

// A VAE for `rest` with the given layer sizes (options.vertices() is replaced by the mesh's).
MeshVae build_mesh_vae(const Mesh& rest, MeshVaeOptions options);

// Writes the VAE's parameters (no buffers: the graph operator is rebuilt from the mesh), the
// optimiser's state if given, and `state`, atomically (save_checkpoint, train/checkpoint.h).
void save_vae_checkpoint(const std::string& path, MeshVaeImpl& vae, torch::optim::Optimizer* optimizer,
                         const CheckpointState& state);
// Reads a checkpoint into `vae` (and `optimizer` if given). Throws retarget::Error naming the
// file for a missing file, another architecture (a parameter missing or of another shape), or
// a checkpoint without optimiser state when one is asked for.
CheckpointState load_vae_checkpoint(const std::string& path, MeshVaeImpl& vae, torch::optim::Optimizer* optimizer);

// A run folder read back: its config, its dataset (checked against the run's fingerprint) and
// the VAE with the weights of checkpoints/<which>.pt.
struct TrainedVae {
  std::string folder;
  VaeTrainConfig config;
  Dataset dataset;
  MeshVae vae{nullptr};
  CheckpointState state;
  std::string checkpoint;  // the file read
};

// The normaliser a VAE trained on `d` with `data` decodes in (VaeDataOptions::target_normaliser):
// the dataset's target_normaliser, or its one normaliser ("shared", and every avatar dataset).
const Normaliser& decoder_normaliser(const Dataset& d, const VaeDataOptions& data);

// which: "best" or "last". Throws retarget::Error for a folder that is not a VAE run, a
// missing checkpoint, or a dataset whose topology differs from the one the run was trained on.
TrainedVae load_trained_vae(const std::string& folder, const std::string& which = "best");

// The latent size of the VAE run in `folder`, from its config.yaml alone (no dataset, no weights).
int64_t vae_run_latent(const std::string& folder);

// Encoder means of raw DR features [N, V, 9] (the run's dataset's reference mesh) -> [N, latent]
// float32, in batches, eval mode, no gradients. clamp_to_range: normalise within the training
// range (Normaliser::normalise_within_range) first. The avatar side uses it for
// deformation-transfer results, which move every vertex a little - including the ones no rig
// controller moves, whose training range is only 1e-5 wide. Unclamped they normalise to values
// in the thousands; clamped to the range's edge they are still values the encoder never saw in
// dimensions it saw constant, and both put the codes far from every avatar sample's.
torch::Tensor encoder_means(TrainedVae& trained, const torch::Tensor& raw_features, bool clamp_to_range = false);

// Exports the VAE as TorchScript (export/vae_export.h) into folder/encoder.pt and
// folder/decoder.pt, with the dataset's normaliser (the decoder: decoder_normaliser), kind, name
// and topology fingerprint.
VaeExportMetadata export_trained_vae(TrainedVae& trained, const std::string& folder);

}  // namespace retarget
