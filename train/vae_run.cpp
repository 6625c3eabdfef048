#include "train/vae_run.h"

#include <fmt/format.h>

#include <filesystem>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/log.h"
#include "core/timer.h"
#include "models/graph_operator.h"
#include "train/run_folder.h"

namespace retarget {

namespace fs = std::filesystem;

MeshVae build_mesh_vae(const Mesh& rest, MeshVaeOptions options) {
  options.vertices(rest.vertex_count());
  options.validate("model");  // before the graph operator and the weights are allocated
  return MeshVae(mesh_graph_operator(rest), options);
}

void save_vae_checkpoint(const std::string& path, MeshVaeImpl& vae, torch::optim::Optimizer* optimizer,
                         const CheckpointState& state) {
  save_checkpoint(path, vae, optimizer, state);
}

CheckpointState load_vae_checkpoint(const std::string& path, MeshVaeImpl& vae, torch::optim::Optimizer* optimizer) {
  return load_checkpoint(path, vae, optimizer, "VAE");
}

const Normaliser& decoder_normaliser(const Dataset& d, const VaeDataOptions& data) {
  return d.kind == DatasetKind::human && data.target_normaliser == "targets" ? d.target_normaliser : d.normaliser;
}

TrainedVae load_trained_vae(const std::string& folder, const std::string& which) {
  if (which != "best" && which != "last") throw Error("--checkpoint", "expected 'best' or 'last', got '" + which + "'");
  const RunStatus status = RunStatus::load(folder);
  if (status.task != "vae") throw Error(folder, "is a '" + status.task + "' run, not a VAE run");
  TrainedVae trained;
  trained.folder = folder;
  const ConfigNode config = ConfigNode::load_file((fs::path(folder) / "config.yaml").string());
  trained.config = read_vae_train_config(config);
  // Runs made before data.target_normaliser existed decoded in the shared ranges.
  if (!config.child("data").has("target_normaliser")) trained.config.data.target_normaliser = "shared";
  trained.dataset = load_dataset(trained.config.data.dataset);
  const auto fingerprint = status.fingerprints.find("dataset");
  if (fingerprint != status.fingerprints.end() && fingerprint->second != trained.dataset.fingerprint)
    throw Error(trained.config.data.dataset,
                fmt::format("its mesh topology (fingerprint {}) is not the one the run in {} was trained on ({})",
                            trained.dataset.fingerprint, folder, fingerprint->second));
  trained.vae = build_mesh_vae(trained.dataset.rest, trained.config.model);
  trained.checkpoint = (fs::path(folder) / "checkpoints" / (which + ".pt")).string();
  if (!fs::exists(trained.checkpoint)) {
    throw Error(trained.checkpoint,
                which == "best" ? "no best checkpoint yet (has the run finished an epoch?)" : "no checkpoint yet");
  }
  trained.state = load_vae_checkpoint(trained.checkpoint, *trained.vae, nullptr);
  trained.vae->eval();
  if (status.status != "finished")
    log::warn("{}: the run has not finished (epoch {} of {})", folder, status.epochs_done, status.epochs_planned);
  return trained;
}

VaeExportMetadata export_trained_vae(TrainedVae& trained, const std::string& folder) {
  const Dataset& d = trained.dataset;
  VaeExportMetadata metadata;
  metadata.kind = to_string(d.kind);
  metadata.name = d.name;
  metadata.fingerprint = d.fingerprint;
  metadata.software_version = RETARGET_VERSION;
  metadata.created = utc_timestamp();
  metadata.vertices = d.vertex_count();
  metadata.latent = trained.vae->options.latent();
  metadata.features = trained.vae->options.features();
  const Normaliser& out = decoder_normaliser(d, trained.config.data);
  export_vae(*trained.vae, d.normaliser.min, d.normaliser.max, metadata, folder, out.min, out.max);
  return metadata;
}

int64_t vae_run_latent(const std::string& folder) {
  return read_vae_train_config(ConfigNode::load_file((std::filesystem::path(folder) / "config.yaml").string()))
      .model.latent();
}

torch::Tensor encoder_means(TrainedVae& trained, const torch::Tensor& raw_features, bool clamp_to_range) {
  constexpr int64_t kBatch = 64;
  torch::NoGradGuard no_grad;
  trained.vae->eval();
  const int64_t n = raw_features.size(0);
  std::vector<torch::Tensor> means;
  for (int64_t begin = 0; begin < n; begin += kBatch) {
    const torch::Tensor x = raw_features.slice(0, begin, std::min(n, begin + kBatch)).to(torch::kFloat32);
    const Normaliser& normaliser = trained.dataset.normaliser;
    const torch::Tensor normalised =
        (clamp_to_range ? normaliser.normalise_within_range(x) : normaliser.normalise(x)).to(torch::kFloat32);
    means.push_back(trained.vae->encode(normalised).mean);
  }
  if (means.empty()) return torch::zeros({0, trained.vae->options.latent()});
  return torch::cat(means, 0).contiguous();
}

}  // namespace retarget
