// The training profiles under configs/train as `retarget train` reads them: their chain of bases
// merged, with the run's files (which no profile names) given as --set overrides.
#pragma once

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/config.h"
#include "scratch.h"
#include "train/train_config.h"

namespace retarget::test {

// The repository's configs/ folder.
inline std::filesystem::path repo_configs() { return std::filesystem::path(RETARGET_SOURCE_DIR) / "configs"; }

// Every .yaml or .yml file under `root`, relative to it ("quick/avatar_vae.yaml"), sorted.
inline std::vector<std::string> yaml_files_under(const std::filesystem::path& root) {
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
    const std::string extension = entry.path().extension().string();
    if (entry.is_regular_file() && (extension == ".yaml" || extension == ".yml"))
      files.push_back(entry.path().lexically_relative(root).generic_string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

// A dataset folder holding only a manifest that names `controllers` controllers: all that
// `model.latent: auto` reads of a dataset (data/dataset.h dataset_controllers).
inline std::string manifest_only_dataset(int controllers) {
  const std::filesystem::path dir = process_scratch_dir("manifest_only_dataset_" + std::to_string(controllers));
  std::string names;
  for (int c = 0; c < controllers; ++c) names += (c ? ", c" : "c") + std::to_string(c);
  std::ofstream(dir / "manifest.yaml") << "format: 1\nkind: avatar\ncontrollers: [" << names << "]\n";
  return dir.string();
}

// The keys that name one run's files: the command line gives them (--set, --out), no profile.
inline const std::vector<std::string>& run_path_keys() {
  static const std::vector<std::string> keys = {"output",          "data.dataset",         "data.human_vae",
                                                "data.avatar_vae", "data.correspondences", "data.triplets"};
  return keys;
}

// The overrides that give a profile of `task` ("vae", "translation" or "cyclegan") its run's files:
// `dataset` (which `latent: auto` reads) and placeholders that the readers do not open.
inline std::vector<std::string> run_path_overrides(const std::string& task, const std::string& dataset) {
  if (task == "vae") return {"data.dataset=" + dataset, "output=runs/vae"};
  if (task == "cyclegan") return {"data.human_vae=runs/human_vae", "data.avatar_vae=runs/avatar_vae", "output=runs/cg"};
  return {"data.human_vae=runs/human_vae", "data.avatar_vae=runs/avatar_vae", "data.correspondences=corr",
          "data.triplets=annotation", "output=runs/translation"};
}

// The profile `file` as `retarget train FILE --set <its run's files>` reads it.
inline ConfigNode load_profile(const std::filesystem::path& file, const std::string& dataset) {
  const std::string task = config_task(load_config_with_overrides(file.string(), {}));
  return load_config_with_overrides(file.string(), run_path_overrides(task, dataset));
}

}  // namespace retarget::test
