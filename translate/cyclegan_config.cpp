#include "translate/cyclegan_config.h"

#include <fmt/format.h>

#include <cmath>

#include "core/error.h"

namespace retarget {

namespace {

void require_checkpoint(const std::string& which, const std::string& key) {
  require(which == "best" || which == "last", key, "expected 'best' or 'last', got '" + which + "'");
}

void require_rate(double lr, const std::string& key) {
  require(std::isfinite(lr) && lr > 0, key, fmt::format("expected a positive number, got {}", lr));
}

}  // namespace

void CycleGanDataOptions::validate(const std::string& path) const {
  require(!human_vae.empty(), key_path(path, "human_vae"), "expected a human VAE run folder");
  require_checkpoint(human_checkpoint, key_path(path, "human_checkpoint"));
  require(!avatar_vae.empty(), key_path(path, "avatar_vae"), "expected an avatar VAE run folder");
  require_checkpoint(avatar_checkpoint, key_path(path, "avatar_checkpoint"));
}

void SimilarityOptions::validate(const std::string& path) const {
  require(samples >= 2, "light_field.samples", fmt::format("expected at least 2 samples per side, got {}", samples));
  require_non_negative(epochs, key_path(path, "epochs"));
  require_rate(lr, key_path(path, "lr"));
  require_positive(batch_size, key_path(path, "batch_size"));
}

void CycleGanLossWeights::validate(const std::string& path) const {
  for (const auto& [name, value] :
       {std::pair<const char*, double>{"adversarial", adversarial}, {"cycle", cycle}, {"similarity", similarity}})
    require(std::isfinite(value) && value >= 0, key_path(path, name),
            fmt::format("expected a number >= 0, got {}", value));
}

void CycleGanTrainConfig::validate() const {
  data.validate();
  light_field.validate();
  similarity.validate();
  model.validate("model");
  require_positive(critic_hidden, "model.critic_hidden");
  loss.validate();
  require_rate(lr, "optimiser.lr");
  training.validate();
  require_positive(training.epochs, "training.epochs");
  require(!output.empty(), "output", "expected a run folder");
}

CycleGanTrainConfig read_cyclegan_train_config(const ConfigNode& root) {
  root.reject_unknown_keys(
      {"task", "data", "light_field", "model", "similarity", "loss", "optimiser", "training", "output"});
  if (config_task(root) != "cyclegan") root.child("task").fail("expected 'cyclegan' for a CycleGAN training config");
  CycleGanTrainConfig config;
  config.source = root.file();

  const ConfigNode data = root.child("data");
  data.reject_unknown_keys({"human_vae", "human_checkpoint", "avatar_vae", "avatar_checkpoint"});
  read_run_path(data, "human_vae", "the human VAE's run folder", config.data.human_vae);
  data.get("human_checkpoint", config.data.human_checkpoint);
  read_run_path(data, "avatar_vae", "the avatar VAE's run folder", config.data.avatar_vae);
  data.get("avatar_checkpoint", config.data.avatar_checkpoint);
  if (root.has("light_field")) {
    const ConfigNode lf = root.child("light_field");
    lf.reject_unknown_keys({"samples", "size", "zernike_order", "fourier"});
    lf.get("samples", config.similarity.samples);
    lf.get("size", config.light_field.size);
    lf.get("zernike_order", config.light_field.zernike_order);
    lf.get("fourier", config.light_field.fourier);
  }
  if (root.has("model")) {
    const ConfigNode model = root.child("model");
    model.reject_unknown_keys({"hidden", "negative_slope", "critic_hidden"});
    int64_t hidden = config.model.hidden();
    double slope = config.model.negative_slope();
    model.get("hidden", hidden);
    model.get("negative_slope", slope);
    model.get("critic_hidden", config.critic_hidden);
    config.model.hidden(hidden).negative_slope(slope);
  }
  if (root.has("similarity")) {
    const ConfigNode s = root.child("similarity");
    s.reject_unknown_keys({"epochs", "lr", "batch_size"});
    s.get("epochs", config.similarity.epochs);
    s.get("lr", config.similarity.lr);
    s.get("batch_size", config.similarity.batch_size);
  }
  if (root.has("loss")) {
    const ConfigNode loss = root.child("loss");
    loss.reject_unknown_keys({"adversarial", "cycle", "similarity"});
    loss.get("adversarial", config.loss.adversarial);
    loss.get("cycle", config.loss.cycle);
    loss.get("similarity", config.loss.similarity);
  }
  if (root.has("optimiser")) {
    const ConfigNode o = root.child("optimiser");
    o.reject_unknown_keys({"lr"});
    o.get("lr", config.lr);
  }
  if (root.has("training")) {
    const ConfigNode training = root.child("training");
    read_training_loop(training, {"epochs"}, config.training);
    training.get("epochs", config.training.epochs);
  }
  return finish_train_config(root, config);
}

std::string to_yaml(const CycleGanTrainConfig& c) {
  YAML::Node root;
  root["task"] = "cyclegan";
  root["data"]["human_vae"] = c.data.human_vae;
  root["data"]["human_checkpoint"] = c.data.human_checkpoint;
  root["data"]["avatar_vae"] = c.data.avatar_vae;
  root["data"]["avatar_checkpoint"] = c.data.avatar_checkpoint;
  root["light_field"]["samples"] = c.similarity.samples;
  root["light_field"]["size"] = c.light_field.size;
  root["light_field"]["zernike_order"] = c.light_field.zernike_order;
  root["light_field"]["fourier"] = c.light_field.fourier;
  root["model"]["hidden"] = c.model.hidden();
  root["model"]["negative_slope"] = c.model.negative_slope();
  root["model"]["critic_hidden"] = c.critic_hidden;
  root["similarity"]["epochs"] = c.similarity.epochs;
  root["similarity"]["lr"] = c.similarity.lr;
  root["similarity"]["batch_size"] = c.similarity.batch_size;
  root["loss"]["adversarial"] = c.loss.adversarial;
  root["loss"]["cycle"] = c.loss.cycle;
  root["loss"]["similarity"] = c.loss.similarity;
  root["optimiser"]["lr"] = c.lr;
  write_training_loop(root["training"], c.training);
  root["training"]["epochs"] = c.training.epochs;
  root["output"] = c.output;
  return config_yaml_text(root);
}

}  // namespace retarget
