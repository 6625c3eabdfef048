#include "translate/translation_config.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <cmath>

#include "core/error.h"

namespace retarget {

const char* to_string(HumanCodes codes) { return codes == HumanCodes::subjects ? "subjects" : "targets"; }

const char* to_string(TripletScale scale) { return scale == TripletScale::group ? "group" : "absolute"; }

void TranslationDataOptions::validate(const std::string& key_path) const {
  require(!human_vae.empty(), retarget::key_path(key_path, "human_vae"), "expected a human VAE run folder");
  require(human_checkpoint == "best" || human_checkpoint == "last", retarget::key_path(key_path, "human_checkpoint"),
          "expected 'best' or 'last', got '" + human_checkpoint + "'");
  require(!avatar_vae.empty(), retarget::key_path(key_path, "avatar_vae"), "expected an avatar VAE run folder");
  require(!correspondences.empty(), retarget::key_path(key_path, "correspondences"),
          "expected a correspondence folder");
  require(held_out_fraction >= 0 && held_out_fraction < 1, retarget::key_path(key_path, "held_out_fraction"),
          fmt::format("expected a number in [0, 1), got {}", held_out_fraction));
}

void LossWeights::validate(const std::string& key_path) const {
  for (const auto& [name, value] :
       {std::pair<const char*, double>{"paired", paired}, {"group", group}, {"triplet", triplet}}) {
    require(std::isfinite(value) && value >= 0, retarget::key_path(key_path, name),
            fmt::format("expected a number >= 0, got {}", value));
  }
}

void StageOptions::validate(const std::string& key_path) const {
  require_non_negative(epochs, retarget::key_path(key_path, "epochs"));
  require(std::isfinite(lr) && lr > 0, retarget::key_path(key_path, "lr"),
          fmt::format("expected a positive number, got {}", lr));
  weights.validate(retarget::key_path(key_path, "weights"));
}

std::vector<StageOptions> paper_stages(int epochs) {
  return {{"paired", epochs, 1e-4, {1.0, 1e-4, 1e-4}},
          {"group", epochs, 1e-5, {1.0, 1.0, 1e-4}},
          {"triplet", epochs, 1e-6, {1.0, 1.0, 10.0}}};
}

void TranslationTrainConfig::validate() const {
  data.validate();
  model.validate("model");
  require(std::isfinite(margin) && margin >= 0, "loss.margin", fmt::format("expected a number >= 0, got {}", margin));
  training.validate();
  require(!stages.empty(), "stages", "expected at least one stage");
  for (size_t s = 0; s < stages.size(); ++s) stages[s].validate(fmt::format("stages[{}]", s));
  require(total_epochs() > 0, "stages", "expected at least one epoch in all (every stage has 0 epochs)");
  require(!output.empty(), "output", "expected a run folder");
}

int TranslationTrainConfig::total_epochs() const {
  return stages.empty() ? 0 : stage_end(static_cast<int>(stages.size()) - 1);
}

int TranslationTrainConfig::stage_end(int stage) const {
  int end = 0;
  for (int s = 0; s <= stage; ++s) end += stages[static_cast<size_t>(s)].epochs;
  return end;
}

int TranslationTrainConfig::stage_of(int epoch) const {
  int end = 0;
  for (size_t s = 0; s < stages.size(); ++s) {
    end += stages[s].epochs;
    if (epoch < end) return static_cast<int>(s);
  }
  TORCH_CHECK(false, "stage_of: epoch ", epoch, " is beyond the last stage (", end, " epochs)");
  return -1;
}

namespace {

LossWeights read_weights(const ConfigNode& node) {
  node.reject_unknown_keys({"paired", "group", "triplet"});
  LossWeights w;
  // All three are required: a stage states its whole loss, nothing comes from another stage.
  node.get_required("paired", w.paired);
  node.get_required("group", w.group);
  node.get_required("triplet", w.triplet);
  return w;
}

StageOptions read_stage(const ConfigNode& node, size_t index) {
  node.reject_unknown_keys({"name", "epochs", "lr", "weights"});
  StageOptions stage;
  stage.name = fmt::format("stage{}", index + 1);
  node.get("name", stage.name);
  node.get_required("epochs", stage.epochs);
  node.get_required("lr", stage.lr);
  stage.weights = read_weights(node.child("weights"));
  stage.validate(node.where());
  return stage;
}

}  // namespace

TranslationTrainConfig read_translation_train_config(const ConfigNode& root) {
  root.reject_unknown_keys({"task", "data", "model", "loss", "training", "stages", "output"});
  if (config_task(root) != "translation")
    root.child("task").fail("expected 'translation' for a translation training config");
  TranslationTrainConfig config;
  config.source = root.file();

  const ConfigNode data = root.child("data");
  data.reject_unknown_keys({"human_vae", "human_checkpoint", "avatar_vae", "correspondences", "triplets",
                            "include_derived", "held_out_fraction", "human_codes", "human_dataset"});
  read_run_path(data, "human_vae", "the human VAE's run folder", config.data.human_vae);
  data.get("human_checkpoint", config.data.human_checkpoint);
  read_run_path(data, "avatar_vae", "the run folder of the avatar VAE the correspondences were built with",
                config.data.avatar_vae);
  read_run_path(data, "correspondences", "the correspondence folder (`retarget correspond --out`)",
                config.data.correspondences);
  if (data.has("triplets") && !data.child("triplets").is_null()) data.get("triplets", config.data.triplets);
  if (data.has("human_dataset") && !data.child("human_dataset").is_null())
    read_run_path(data, "human_dataset", "the human dataset F learns from", config.data.human_dataset);
  data.get("include_derived", config.data.include_derived);
  data.get("held_out_fraction", config.data.held_out_fraction);
  if (data.has("human_codes")) {
    const std::string codes = data.child("human_codes").as<std::string>();
    if (codes == "subjects") {
      config.data.human_codes = HumanCodes::subjects;
    } else if (codes == "targets") {
      config.data.human_codes = HumanCodes::targets;
    } else {
      data.child("human_codes").fail("expected 'subjects' or 'targets', got '" + codes + "'");
    }
  }
  validate_in(root, [&] { config.data.validate(); });

  if (root.has("model")) {
    const ConfigNode model = root.child("model");
    model.reject_unknown_keys({"hidden", "negative_slope"});
    int64_t hidden = config.model.hidden();
    double slope = config.model.negative_slope();
    model.get("hidden", hidden);
    model.get("negative_slope", slope);
    config.model.hidden(hidden).negative_slope(slope);
    require_positive(static_cast<double>(hidden), model.where() + ".hidden");
    require_non_negative(slope, model.where() + ".negative_slope");
  }
  if (root.has("loss")) {
    const ConfigNode loss = root.child("loss");
    loss.reject_unknown_keys({"margin", "triplet_scale"});
    loss.get("margin", config.margin);
    if (!(config.margin >= 0) || !std::isfinite(config.margin))
      loss.child("margin").fail(fmt::format("expected a number >= 0, got {}", config.margin));
    if (loss.has("triplet_scale")) {
      const std::string scale = loss.child("triplet_scale").as<std::string>();
      if (scale == "group") {
        config.triplet_scale = TripletScale::group;
      } else if (scale == "absolute") {
        config.triplet_scale = TripletScale::absolute;
      } else {
        loss.child("triplet_scale").fail("expected 'group' or 'absolute', got '" + scale + "'");
      }
    }
  }
  if (root.has("training")) {
    const ConfigNode training = root.child("training");
    read_training_loop(training, {"input_noise"}, config.training);
    training.get("input_noise", config.training.input_noise);
    if (!std::isfinite(config.training.input_noise) || config.training.input_noise < 0)
      training.child("input_noise")
          .fail(fmt::format("expected a finite number >= 0 (a multiple of the codes' spread), got {}",
                            config.training.input_noise));
    validate_in(root, [&] { config.training.validate(); });
  }
  if (root.has("stages")) {
    const ConfigNode stages = root.child("stages");
    if (!stages.is_sequence()) stages.fail("expected a list of stages ({name, epochs, lr, weights})");
    config.stages.clear();
    for (size_t s = 0; s < stages.size(); ++s) config.stages.push_back(read_stage(stages.at(s), s));
    if (config.stages.empty()) stages.fail("expected at least one stage");
  }
  return finish_train_config(root, config);
}

std::string to_yaml(const TranslationTrainConfig& c) {
  YAML::Node root;
  root["task"] = "translation";
  root["data"]["human_vae"] = c.data.human_vae;
  root["data"]["human_checkpoint"] = c.data.human_checkpoint;
  root["data"]["avatar_vae"] = c.data.avatar_vae;
  root["data"]["correspondences"] = c.data.correspondences;
  root["data"]["triplets"] = c.data.triplets;
  if (!c.data.human_dataset.empty()) root["data"]["human_dataset"] = c.data.human_dataset;
  root["data"]["include_derived"] = c.data.include_derived;
  root["data"]["held_out_fraction"] = c.data.held_out_fraction;
  root["data"]["human_codes"] = to_string(c.data.human_codes);
  root["model"]["hidden"] = c.model.hidden();
  root["model"]["negative_slope"] = c.model.negative_slope();
  root["loss"]["margin"] = c.margin;
  root["loss"]["triplet_scale"] = to_string(c.triplet_scale);
  write_training_loop(root["training"], c.training);
  root["training"]["input_noise"] = c.training.input_noise;
  for (const StageOptions& s : c.stages) {
    YAML::Node stage;
    stage["name"] = s.name;
    stage["epochs"] = s.epochs;
    stage["lr"] = s.lr;
    stage["weights"]["paired"] = s.weights.paired;
    stage["weights"]["group"] = s.weights.group;
    stage["weights"]["triplet"] = s.weights.triplet;
    root["stages"].push_back(stage);
  }
  root["output"] = c.output;
  return config_yaml_text(root);
}

}  // namespace retarget
