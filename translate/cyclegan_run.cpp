#include "translate/cyclegan_run.h"

#include <fmt/format.h>

#include <filesystem>

#include "core/error.h"
#include "core/log.h"
#include "train/run_folder.h"
#include "train/vae_run.h"
#include "translate/translation_run.h"

namespace retarget {

namespace fs = std::filesystem;

namespace {

// The VAE run of `key`, refused when its dataset is not the one the CycleGAN was trained on.
TrainedVae vae_of(const TrainedCycleGan& trained, const std::string& folder, const std::string& which,
                  const std::string& key) {
  TrainedVae vae = load_trained_vae(folder, which);
  const auto known = RunStatus::load(trained.folder).fingerprints;
  const auto it = known.find(key);
  if (it != known.end() && it->second != vae.dataset.fingerprint)
    throw Error(vae.dataset.folder, fmt::format("its topology (fingerprint {}) is not the one the CycleGAN run in {} "
                                                "was trained with ({})",
                                                vae.dataset.fingerprint, trained.folder, it->second));
  return vae;
}

}  // namespace

TrainedCycleGan load_trained_cyclegan(const std::string& folder) {
  const RunStatus status = RunStatus::load(folder);
  if (status.task != "cyclegan") throw Error(folder, "is a '" + status.task + "' run, not a CycleGAN run");
  TrainedCycleGan trained;
  trained.folder = folder;
  trained.config = read_cyclegan_train_config(ConfigNode::load_file((fs::path(folder) / "config.yaml").string()));
  LatentCycleGanOptions model;
  model.generator = trained.config.model;
  model.generator.latent_in(vae_run_latent(trained.config.data.human_vae))
      .latent_out(vae_run_latent(trained.config.data.avatar_vae));
  model.critic_hidden = trained.config.critic_hidden;
  trained.net = LatentCycleGan(model);
  const std::string checkpoint = (fs::path(folder) / "checkpoints" / "last.pt").string();
  if (!fs::exists(checkpoint)) throw Error(checkpoint, "no checkpoint yet");
  trained.state = load_checkpoint(checkpoint, *trained.net, nullptr, "CycleGAN");
  trained.net->eval();
  if (status.status != "finished")
    log::warn("{}: the run has not finished (epoch {} of {})", folder, status.epochs_done, status.epochs_planned);
  return trained;
}

BundleParts cyclegan_bundle_parts(const TrainedCycleGan& trained) {
  const CycleGanDataOptions& data = trained.config.data;
  const TrainedVae human = vae_of(trained, data.human_vae, data.human_checkpoint, "human_dataset");
  const TrainedVae avatar = vae_of(trained, data.avatar_vae, data.avatar_checkpoint, "avatar_dataset");
  return bundle_parts_between(human, trained.net->to_avatar, avatar);
}

}  // namespace retarget
