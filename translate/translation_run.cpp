#include "translate/translation_run.h"

#include <fmt/format.h>

#include <filesystem>
#include <optional>
#include <regex>

#include "core/error.h"
#include "core/log.h"
#include "correspond/correspondence.h"
#include "data/still_vertices.h"
#include "geometry/metrics.h"
#include "geometry/rig.h"
#include "geometry/topology_fingerprint.h"
#include "train/run_folder.h"
#include "train/vae_run.h"

namespace retarget {

namespace fs = std::filesystem;

namespace {

BundleSide bundle_side(const TrainedVae& trained) {
  BundleSide side;
  side.vae = trained.vae;
  side.normaliser_min = trained.dataset.normaliser.min;
  side.normaliser_max = trained.dataset.normaliser.max;
  side.rest = trained.dataset.rest;
  side.dr = trained.dataset.dr;
  side.name = trained.dataset.name;
  side.units = trained.dataset.units;
  if (trained.dataset.kind == DatasetKind::avatar) side.still_vertices = still_vertices(trained.dataset);
  return side;
}

// The avatar dataset's rig for the bundle (retarget-infer --weights), with the dataset's scale; none
// (and a warning) when the rig no longer loads or no longer fits the dataset: the bundle is still
// useful for meshes.
std::optional<BundleRig> bundle_rig(const Dataset& avatar) {
  BundleRig part;
  try {
    part.rig = load_dataset_rig(avatar);  // the glTF meshes it was built from; checks the topology
    if (part.rig.controllers.empty()) throw Error(avatar.source, "has no controllers");
  } catch (const Error& e) {
    log::warn(
        "{}: the avatar dataset's rig does not load ({}); the bundle is exported without a rig, so "
        "retarget-infer --weights will be unavailable for it",
        avatar.folder, e.what());
    return std::nullopt;
  }
  if (!avatar.eyes.left.empty() && !avatar.eyes.right.empty()) {
    try {
      part.millimetres_per_unit = millimetres_per_unit(avatar.rest.vertices, avatar.eyes);
    } catch (const Error& e) {
      log::warn("{}: no millimetre scale from the eye landmarks ({}); weight residuals will be in mesh units",
                avatar.folder, e.what());
    }
  }
  return part;
}

}  // namespace

TrainedTranslation load_trained_translation(const std::string& folder, const std::string& which) {
  const RunStatus status = RunStatus::load(folder);
  if (status.task != "translation") throw Error(folder, "is a '" + status.task + "' run, not a translation run");
  TrainedTranslation trained;
  trained.folder = folder;
  trained.config = read_translation_train_config(ConfigNode::load_file((fs::path(folder) / "config.yaml").string()));
  const std::string stages = fmt::format("stage1 .. stage{}", trained.config.stages.size());
  std::smatch match;
  if (which != "last") {
    static const std::regex stage_name("stage([0-9]+)");
    const bool is_stage = std::regex_match(which, match, stage_name);
    const int n = is_stage ? std::stoi(match[1].str()) : 0;
    if (!is_stage || n < 1 || n > static_cast<int>(trained.config.stages.size()))
      throw Error("--checkpoint", fmt::format("expected 'last' or one of {} for this run, got '{}'", stages, which));
  }
  trained.checkpoint = (fs::path(folder) / "checkpoints" / (which + ".pt")).string();
  if (!fs::exists(trained.checkpoint))
    throw Error(trained.checkpoint,
                which == "last" ? "no checkpoint yet" : "no such snapshot yet (the stage has not ended)");

  TranslationMlpOptions model = trained.config.model;
  model.latent_in(vae_run_latent(trained.config.data.human_vae))
      .latent_out(vae_run_latent(trained.config.data.avatar_vae));
  trained.translation = TranslationMlp(model);
  trained.state = load_checkpoint(trained.checkpoint, *trained.translation, nullptr, "translation");
  trained.translation->eval();
  if (status.status != "finished")
    log::warn("{}: the run has not finished (epoch {} of {})", folder, status.epochs_done, status.epochs_planned);
  return trained;
}

BundleParts translation_bundle_parts(const TrainedTranslation& trained) {
  const TranslationDataOptions& data = trained.config.data;
  const Correspondences c = load_correspondences(data.correspondences);
  const TrainedVae human = load_trained_vae(data.human_vae, data.human_checkpoint);
  const TrainedVae avatar = load_trained_vae(data.avatar_vae, c.avatar_vae_checkpoint);
  check_correspondences(c, human.dataset, avatar.dataset);
  const RunStatus status = RunStatus::load(trained.folder);
  for (const auto& [key, dataset] :
       {std::pair<std::string, const Dataset*>{"human_dataset", &human.dataset}, {"avatar_dataset", &avatar.dataset}}) {
    const auto known = status.fingerprints.find(key);
    if (known != status.fingerprints.end() && known->second != dataset->fingerprint)
      throw Error(dataset->folder, fmt::format("its topology (fingerprint {}) is not the one the translation run in {} "
                                               "was trained with ({})",
                                               dataset->fingerprint, trained.folder, known->second));
  }
  return bundle_parts_between(human, trained.translation, avatar);
}

BundleParts bundle_parts_between(const TrainedVae& human, const TranslationMlp& translation, const TrainedVae& avatar) {
  BundleParts parts;
  parts.human = bundle_side(human);
  parts.translation = translation;
  parts.avatar = bundle_side(avatar);
  parts.rig = bundle_rig(avatar.dataset);
  return parts;
}

}  // namespace retarget
