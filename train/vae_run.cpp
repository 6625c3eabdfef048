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
  return MeshVae(mesh_graph_operator(rest), options);
}

void save_vae_checkpoint(const std::string& path, MeshVaeImpl& vae, torch::optim::Optimizer* optimizer,
                         const CheckpointState& state) {
  torch::serialize::OutputArchive archive;
  torch::serialize::OutputArchive weights;
  for (const auto& p : vae.named_parameters()) weights.write(p.key(), p.value().detach());
  archive.write("weights", weights);
  if (optimizer) {
    torch::serialize::OutputArchive optimiser_archive;
    optimizer->save(optimiser_archive);
    archive.write("optimiser", optimiser_archive);
  }
  archive.write("epoch", torch::tensor(static_cast<int64_t>(state.epoch)));
  archive.write("best_epoch", torch::tensor(static_cast<int64_t>(state.best_epoch)));
  archive.write("best_validation", torch::tensor(state.best_validation, torch::kFloat64));
  const std::string temporary = temporary_path_for(path);
  try {
    archive.save_to(temporary);
    commit_temporary_file(temporary, path);
  } catch (const c10::Error& e) {
    discard_temporary_file(temporary);
    throw Error(path, std::string("cannot write the checkpoint: ") + e.what_without_backtrace());
  } catch (...) {
    discard_temporary_file(temporary);
    throw;
  }
}

CheckpointState load_vae_checkpoint(const std::string& path, MeshVaeImpl& vae, torch::optim::Optimizer* optimizer) {
  if (!fs::exists(path)) throw Error(path, "no such checkpoint");
  torch::serialize::InputArchive archive;
  try {
    archive.load_from(path);
  } catch (const c10::Error& e) {
    throw Error(path, std::string("not a readable checkpoint: ") + e.what_without_backtrace());
  }
  torch::serialize::InputArchive weights;
  if (!archive.try_read("weights", weights)) throw Error(path, "not a VAE checkpoint (no weights)");
  {
    torch::NoGradGuard no_grad;
    for (auto& p : vae.named_parameters()) {
      torch::Tensor value;
      if (!weights.try_read(p.key(), value))
        throw Error(path, fmt::format("has no parameter '{}': trained with another architecture?", p.key()));
      if (value.sizes() != p.value().sizes())
        throw Error(path, fmt::format("parameter '{}' is {} in the checkpoint but {} in the model (model sizes "
                                      "differ from the config it was trained with?)",
                                      p.key(), c10::str(value.sizes()), c10::str(p.value().sizes())));
      p.value().copy_(value);
    }
  }
  if (optimizer) {
    torch::serialize::InputArchive optimiser_archive;
    if (!archive.try_read("optimiser", optimiser_archive)) throw Error(path, "holds no optimiser state to resume from");
    optimizer->load(optimiser_archive);
  }
  CheckpointState state;
  torch::Tensor t;
  if (archive.try_read("epoch", t)) state.epoch = static_cast<int>(t.item<int64_t>());
  if (archive.try_read("best_epoch", t)) state.best_epoch = static_cast<int>(t.item<int64_t>());
  if (archive.try_read("best_validation", t)) state.best_validation = t.item<double>();
  return state;
}

TrainedVae load_trained_vae(const std::string& folder, const std::string& which) {
  if (which != "best" && which != "last") throw Error("--checkpoint", "expected 'best' or 'last', got '" + which + "'");
  const RunStatus status = RunStatus::load(folder);
  if (status.task != "vae") throw Error(folder, "is a '" + status.task + "' run, not a VAE run");
  TrainedVae trained;
  trained.folder = folder;
  trained.config = read_vae_train_config(ConfigNode::load_file((fs::path(folder) / "config.yaml").string()));
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
  export_vae(*trained.vae, d.normaliser.min, d.normaliser.max, metadata, folder);
  return metadata;
}

}  // namespace retarget
