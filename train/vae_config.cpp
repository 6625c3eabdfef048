#include "train/vae_config.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/log.h"
#include "data/dataset.h"

namespace retarget {

void VaeDataOptions::validate(const std::string& key_path) const {
  require(!dataset.empty(), retarget::key_path(key_path, "dataset"), "expected a dataset folder");
  require(validation_fraction >= 0 && validation_fraction < 1, retarget::key_path(key_path, "validation_fraction"),
          fmt::format("expected a number in [0, 1), got {}", validation_fraction));
  require(target_normaliser == "targets" || target_normaliser == "shared",
          retarget::key_path(key_path, "target_normaliser"),
          fmt::format("expected 'targets' or 'shared', got '{}'", target_normaliser));
}

void OptimiserOptions::validate(const std::string& key_path) const {
  require_positive(lr, retarget::key_path(key_path, "lr"));
  require(beta1 >= 0 && beta1 < 1 && beta2 >= 0 && beta2 < 1, retarget::key_path(key_path, "betas"),
          fmt::format("expected two numbers in [0, 1), got [{}, {}]", beta1, beta2));
  require_non_negative(weight_decay, retarget::key_path(key_path, "weight_decay"));
}

void ScheduleOptions::validate(const std::string& key_path) const {
  require(decay > 0 && decay <= 1, retarget::key_path(key_path, "decay"),
          fmt::format("expected a number in (0, 1], got {}", decay));
  require_positive(every, retarget::key_path(key_path, "every"));
}

double ScheduleOptions::lr_at(double lr, int epoch) const { return lr * std::pow(decay, epoch / every); }

void TrainingOptions::validate(const std::string& key_path) const {
  require_positive(epochs, retarget::key_path(key_path, "epochs"));
  TrainingLoopOptions::validate(key_path);
}

void VaeTrainConfig::validate() const {
  data.validate();
  model.validate("model");
  require(model.features() == 9, "model.channels[0]",
          fmt::format("expected 9 (the DR feature width), got {}", model.features()));
  require(!model.encoder_skip() || decoder_start == DecoderStart::principal, "model.encoder_skip",
          "needs model.decoder_start: principal (the skip is fitted to the principal codes, not trained)");
  require(std::isfinite(kl_weight) && kl_weight >= 0, "loss.kl_weight",
          fmt::format("expected a number >= 0, got {}", kl_weight));
  optimiser.validate();
  schedule.validate();
  training.validate();
  require(!output.empty(), "output", "expected a run folder");
}

int64_t automatic_latent(const std::string& dataset, const ConfigNode& where) {
  std::vector<std::string> controllers;
  try {
    controllers = dataset_controllers(dataset);
  } catch (const Error& e) {
    where.fail(fmt::format("'auto' sizes the latent by the dataset's controllers, but {}", e.what()));
  }
  const int64_t latent = std::max<int64_t>(kPaperLatent, static_cast<int64_t>(controllers.size()));
  log::info("model.latent: auto -> {} ({} controllers; at least the paper's {})", latent, controllers.size(),
            kPaperLatent);
  return latent;
}

VaeTrainConfig read_vae_train_config(const ConfigNode& root) {
  root.reject_unknown_keys({"task", "data", "model", "loss", "optimiser", "schedule", "training", "output"});
  if (config_task(root) != "vae") root.child("task").fail("expected 'vae' for a VAE training config");
  VaeTrainConfig config;
  config.source = root.file();

  const ConfigNode data = root.child("data");
  data.reject_unknown_keys({"dataset", "validation_fraction", "target_normaliser"});
  read_run_path(data, "dataset", "the dataset folder (`retarget dataset --out`)", config.data.dataset);
  config.data.dataset_where = data.child("dataset").where();
  data.get("validation_fraction", config.data.validation_fraction);
  data.get("target_normaliser", config.data.target_normaliser);

  if (root.has("model")) {
    const ConfigNode model = root.child("model");
    model.reject_unknown_keys({"channels", "hidden", "latent", "order", "decoder_start", "encoder_skip"});
    std::vector<int64_t> channels = config.model.channels();
    int64_t hidden = config.model.hidden(), latent = config.model.latent(), order = config.model.order();
    model.get("channels", channels);
    model.get("hidden", hidden);
    if (model.has("latent") && model.child("latent").as<std::string>() == "auto") {
      latent = automatic_latent(config.data.dataset, model.child("latent"));
    } else {
      model.get("latent", latent);
    }
    model.get("order", order);
    bool encoder_skip = config.model.encoder_skip();
    model.get("encoder_skip", encoder_skip);
    config.model.channels(channels).hidden(hidden).latent(latent).order(order).encoder_skip(encoder_skip);
    if (model.has("decoder_start")) {
      const ConfigNode start = model.child("decoder_start");
      const auto name = start.as<std::string>();
      if (name == "random")
        config.decoder_start = DecoderStart::random;
      else if (name == "principal")
        config.decoder_start = DecoderStart::principal;
      else
        start.fail(fmt::format("expected 'random' or 'principal', got '{}'", name));
    }
    if (encoder_skip && config.decoder_start != DecoderStart::principal)
      model.child("encoder_skip")
          .fail("needs model.decoder_start: principal (the skip is fitted to the principal codes, not trained)");
    validate_in(root, [&] { config.model.validate("model"); });
  }
  if (root.has("loss")) {
    const ConfigNode loss = root.child("loss");
    loss.reject_unknown_keys({"kl_weight", "reconstruction"});
    loss.get("kl_weight", config.kl_weight);
    if (loss.has("reconstruction")) {
      const ConfigNode reconstruction = loss.child("reconstruction");
      try {
        config.reconstruction = parse_reconstruction_loss(reconstruction.as<std::string>(), reconstruction.where());
      } catch (const Error& e) {
        reconstruction.fail(e.detail());
      }
    }
    if (!(config.kl_weight >= 0) || !std::isfinite(config.kl_weight))
      loss.child("kl_weight").fail(fmt::format("expected a number >= 0, got {}", config.kl_weight));
  }
  if (root.has("optimiser")) {
    const ConfigNode opt = root.child("optimiser");
    opt.reject_unknown_keys({"lr", "betas", "weight_decay"});
    opt.get("lr", config.optimiser.lr);
    if (opt.has("betas")) {
      const std::vector<double> betas = opt.child("betas").as<std::vector<double>>();
      if (betas.size() != 2) opt.child("betas").fail(fmt::format("expected two numbers, got {}", betas.size()));
      config.optimiser.beta1 = betas[0];
      config.optimiser.beta2 = betas[1];
    }
    opt.get("weight_decay", config.optimiser.weight_decay);
    validate_in(root, [&] { config.optimiser.validate(); });
  }
  if (root.has("schedule")) {
    const ConfigNode schedule = root.child("schedule");
    schedule.reject_unknown_keys({"decay", "every"});
    schedule.get("decay", config.schedule.decay);
    schedule.get("every", config.schedule.every);
    validate_in(root, [&] { config.schedule.validate(); });
  }
  if (root.has("training")) {
    const ConfigNode training = root.child("training");
    read_training_loop(training, {"epochs"}, config.training);
    training.get("epochs", config.training.epochs);
    validate_in(root, [&] { config.training.validate(); });
  }
  return finish_train_config(root, config);
}

std::string to_yaml(const VaeTrainConfig& c) {
  YAML::Node root;
  root["task"] = "vae";
  root["data"]["dataset"] = c.data.dataset;
  root["data"]["validation_fraction"] = c.data.validation_fraction;
  root["data"]["target_normaliser"] = c.data.target_normaliser;
  root["model"]["channels"] = flow_style(YAML::Node(c.model.channels()));
  root["model"]["hidden"] = c.model.hidden();
  root["model"]["latent"] = c.model.latent();
  root["model"]["order"] = c.model.order();
  root["model"]["decoder_start"] = c.decoder_start == DecoderStart::principal ? "principal" : "random";
  root["model"]["encoder_skip"] = c.model.encoder_skip();
  root["loss"]["kl_weight"] = c.kl_weight;
  root["loss"]["reconstruction"] = to_string(c.reconstruction);
  root["optimiser"]["lr"] = c.optimiser.lr;
  root["optimiser"]["betas"] = flow_style(YAML::Node(std::vector<double>{c.optimiser.beta1, c.optimiser.beta2}));
  root["optimiser"]["weight_decay"] = c.optimiser.weight_decay;
  root["schedule"]["decay"] = c.schedule.decay;
  root["schedule"]["every"] = c.schedule.every;
  root["training"]["epochs"] = c.training.epochs;
  write_training_loop(root["training"], c.training);
  root["output"] = c.output;
  return config_yaml_text(root);
}

}  // namespace retarget
