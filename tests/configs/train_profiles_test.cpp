// The training profiles under configs/train: a base (the paper's settings) and overlays on it that
// state what they change (quick/ over the base, good/ over quick/). Their merged values are the
// ones the full files had before they became overlays, none of them names a run's files, and an
// overlay states nothing its base already says.
#include "tests/configs/train_profiles.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/config_base.h"
#include "core/error.h"
#include "train/train_config.h"
#include "train/vae_config.h"
#include "translate/translation_config.h"

using namespace retarget;
using namespace retarget::test;
using Catch::Contains;
namespace fs = std::filesystem;

namespace {

// Every YAML file under configs/train, relative to configs/train, sorted.
std::vector<std::string> train_config_files() { return yaml_files_under(repo_configs() / "train"); }

fs::path profile(const std::string& relative) { return repo_configs() / "train" / relative; }

// The values of a VAE profile that its full file stated (the paper's, quick and good).
struct VaeProfile {
  const char* file;
  std::vector<int64_t> channels;
  int64_t latent;  // with a 4-controller dataset (`auto`: the paper's 25)
  DecoderStart start;
  bool encoder_skip;
  double kl_weight;
  ReconstructionLoss reconstruction;
  double lr, decay;
  int every, epochs, batch_size;
};

// The values of a translation profile that its full file stated.
struct TranslationProfile {
  const char* file;
  HumanCodes codes;
  TripletScale scale;
  int batch_size, checkpoint_every;
  double input_noise;
  std::vector<int> stage_epochs;
  std::vector<double> stage_lr, group_weight, triplet_weight;
};

}  // namespace

TEST_CASE("train profiles: every VAE profile has the values its full file had", "[config][train]") {
  const std::vector<int64_t> paper = {9, 128, 64, 64, 64, 1}, quick = {9, 32, 16, 16, 16, 1},
                             good = {9, 64, 32, 32, 32, 1};
  const auto l1 = ReconstructionLoss::l1, squared = ReconstructionLoss::squared;
  const auto random = DecoderStart::random, principal = DecoderStart::principal;
  const std::vector<VaeProfile> profiles = {
      {"avatar_vae.yaml", paper, 25, random, false, 1e-5, l1, 1e-4, 0.6, 10, 100, 30},
      {"human_vae.yaml", paper, 25, random, false, 1e-5, l1, 1e-4, 1.0, 10, 20, 1},
      {"quick/avatar_vae.yaml", quick, 25, principal, true, 1e-6, squared, 3e-4, 0.6, 3, 10, 30},
      {"quick/human_vae.yaml", quick, 25, principal, true, 1e-5, l1, 1e-3, 0.6, 2, 6, 10},
      {"good/avatar_vae.yaml", good, 25, principal, true, 1e-6, squared, 3e-4, 0.7, 6, 24, 30},
      {"good/human_vae.yaml", quick, 25, principal, true, 1e-5, l1, 1e-3, 0.7, 6, 30, 10},
  };
  const std::string dataset = manifest_only_dataset(4);
  for (const VaeProfile& p : profiles) {
    INFO(p.file);
    const VaeTrainConfig c = read_vae_train_config(load_profile(profile(p.file), dataset));
    CHECK(c.model.channels() == p.channels);
    CHECK(c.model.hidden() == 300);
    CHECK(c.model.latent() == p.latent);
    CHECK(c.model.order() == 2);
    CHECK(c.decoder_start == p.start);
    CHECK(c.model.encoder_skip() == p.encoder_skip);
    CHECK(c.kl_weight == p.kl_weight);
    CHECK(c.reconstruction == p.reconstruction);
    CHECK(c.optimiser.lr == p.lr);
    CHECK(c.optimiser.beta1 == 0.9);
    CHECK(c.optimiser.beta2 == 0.999);
    CHECK(c.optimiser.weight_decay == 0);
    CHECK(c.schedule.decay == p.decay);
    CHECK(c.schedule.every == p.every);
    CHECK(c.training.epochs == p.epochs);
    CHECK(c.training.batch_size == p.batch_size);
    CHECK(c.training.checkpoint_every == 1);
    CHECK(c.training.seed == 1);
    CHECK(c.training.threads == 0);
    CHECK(c.data.validation_fraction == 0.1);
    CHECK(c.data.target_normaliser == "targets");
    CHECK(c.data.dataset == dataset);
    CHECK(c.output == "runs/vae");
  }
  // `latent: auto` stays auto through the chain: a rig with more controllers than 25 widens it.
  const std::string many = manifest_only_dataset(40);
  CHECK(read_vae_train_config(load_profile(profile("quick/avatar_vae.yaml"), many)).model.latent() == 40);
  CHECK(read_vae_train_config(load_profile(profile("good/avatar_vae.yaml"), many)).model.latent() == 40);
  CHECK(read_vae_train_config(load_profile(profile("good/human_vae.yaml"), many)).model.latent() == 25);
}

TEST_CASE("train profiles: every translation profile has the values its full file had", "[config][train]") {
  const std::vector<TranslationProfile> profiles = {
      {"translation.yaml",
       HumanCodes::targets,
       TripletScale::absolute,
       32,
       50,
       0,
       {3000, 3000, 3000},
       {1e-4, 1e-5, 1e-6},
       {1e-4, 1, 1},
       {1e-4, 1e-4, 10}},
      {"quick/translation.yaml",
       HumanCodes::subjects,
       TripletScale::group,
       64,
       25,
       4,
       {200, 150, 150},
       {1e-3, 3e-4, 1e-4},
       {1e-4, 0.1, 0.1},
       {1e-4, 1e-4, 10}},
      {"good/translation.yaml",
       HumanCodes::subjects,
       TripletScale::group,
       64,
       25,
       4,
       {400, 300, 300},
       {1e-3, 3e-4, 1e-4},
       {1e-4, 0.1, 0.1},
       {1e-4, 1e-4, 10}},
  };
  for (const TranslationProfile& p : profiles) {
    INFO(p.file);
    const TranslationTrainConfig c = read_translation_train_config(load_profile(profile(p.file), ""));
    CHECK(c.data.human_checkpoint == "best");
    CHECK(c.data.include_derived);
    CHECK(c.data.held_out_fraction == 0.2);
    CHECK(c.data.human_codes == p.codes);
    CHECK(c.data.human_vae == "runs/human_vae");
    CHECK(c.data.triplets == "annotation");
    CHECK(c.model.hidden() == 100);
    CHECK(c.model.negative_slope() == 0.1);
    CHECK(c.margin == 0.2);
    CHECK(c.triplet_scale == p.scale);
    CHECK(c.training.batch_size == p.batch_size);
    CHECK(c.training.checkpoint_every == p.checkpoint_every);
    CHECK(c.training.seed == 1);
    CHECK(c.training.threads == 1);
    CHECK(c.training.input_noise == p.input_noise);
    REQUIRE(c.stages.size() == 3);
    const std::vector<std::string> names = {"paired", "group", "triplet"};
    for (size_t s = 0; s < 3; ++s) {
      INFO("stage " << s);
      CHECK(c.stages[s].name == names[s]);
      CHECK(c.stages[s].epochs == p.stage_epochs[s]);
      CHECK(c.stages[s].lr == p.stage_lr[s]);
      CHECK(c.stages[s].weights.paired == 1);
      CHECK(c.stages[s].weights.group == p.group_weight[s]);
      CHECK(c.stages[s].weights.triplet == p.triplet_weight[s]);
    }
    CHECK(c.output == "runs/translation");
  }
}

TEST_CASE("train profiles: no profile names a run's files, the command line gives them", "[config][train]") {
  const std::vector<std::string> files = train_config_files();
  REQUIRE(files.size() >= 9);
  for (const std::string& file : files) {
    INFO(file);
    for (const ConfigNode& root :
         {ConfigNode::load_file(profile(file).string()), load_config_with_bases(profile(file).string())}) {
      for (const std::string& key : run_path_keys()) {
        const size_t dot = key.find('.');
        const bool held = dot == std::string::npos
                              ? root.has(key)
                              : root.has(key.substr(0, dot)) && root.child(key.substr(0, dot)).has(key.substr(dot + 1));
        CHECK_FALSE(held);
        if (held) UNSCOPED_INFO(file << " holds " << key);
      }
    }
  }
  // Without them a profile says which is missing and how to give it.
  CHECK_THAT(error_of([] {
               read_vae_train_config(load_config_with_overrides(profile("quick/avatar_vae.yaml").string(), {}));
             }),
             Contains("quick/avatar_vae.yaml: data.dataset: missing: the dataset folder") &&
                 Contains("give it with --set data.dataset=PATH"));
  CHECK_THAT(
      error_of([] {
        read_vae_train_config(load_config_with_overrides(profile("good/human_vae.yaml").string(), {"data.dataset=ds"}));
      }),
      Contains("good/human_vae.yaml: output: missing: the run folder") &&
          Contains("`retarget train CONFIG --out DIR` (or --set output=DIR)"));
  CHECK_THAT(error_of([] {
               read_translation_train_config(
                   load_config_with_overrides(profile("good/translation.yaml").string(), {"data.human_vae=h"}));
             }),
             Contains("good/translation.yaml: data.avatar_vae: missing") &&
                 Contains("give it with --set data.avatar_vae=PATH"));
}

TEST_CASE("train profiles: an overlay states only what differs from its base", "[config][train]") {
  size_t overlays = 0;
  for (const std::string& file : train_config_files()) {
    const ConfigNode own = ConfigNode::load_file(profile(file).string());
    if (!own.has("base")) continue;
    ++overlays;
    const fs::path base_file = (profile(file).parent_path() / own.child("base").as<std::string>()).lexically_normal();
    const ConfigNode base = load_config_with_bases(base_file.string());
    // Each value the overlay gives (a scalar or a list; maps are walked into) against the base's.
    std::vector<std::pair<YAML::Node, YAML::Node>> pending = {{own.yaml(), base.yaml()}};
    std::vector<std::string> paths = {""};
    while (!pending.empty()) {
      const auto [mine, theirs] = pending.back();
      const std::string path = paths.back();
      pending.pop_back();
      paths.pop_back();
      for (const auto& entry : mine) {
        const std::string key = entry.first.Scalar();
        if (path.empty() && key == "base") continue;
        const YAML::Node other = theirs[key];
        if (!other.IsDefined()) continue;
        if (entry.second.IsMap() && other.IsMap()) {
          pending.emplace_back(entry.second, other);
          paths.push_back(key_path(path, key));
          continue;
        }
        INFO(file << ": " << key_path(path, key) << " restates its base's value");
        CHECK(YAML::Dump(entry.second) != YAML::Dump(other));
      }
    }
  }
  CHECK(overlays >= 6);  // quick/ and good/
}
