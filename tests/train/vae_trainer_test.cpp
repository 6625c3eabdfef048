#include "train/vae_trainer.h"

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "cli/cli.h"
#include "cli/commands.h"
#include "core/error.h"
#include "data/dataset.h"
#include "eval/vae_evaluation.h"
#include "test_support.h"
#include "tests/train/vae_train_options.h"
#include "tiny_data.h"
#include "train/checkpoint.h"
#include "train/train_config.h"
#include "train/vae_run.h"

using namespace retarget;
using namespace retarget::test;
namespace fs = std::filesystem;

namespace {

// A 64-vertex avatar dataset of 60 rig samples (built once per test binary).
std::string avatar_dataset() {
  static const std::string folder = build_tiny_avatar_dataset("vae_trainer_avatar_data", tiny_rig(7), 60, 0.2, 2);
  return folder;
}

std::string human_dataset() {
  static const std::string folder = build_tiny_human_dataset("vae_trainer_human_data", 8, 3, 4);
  return folder;
}

// A small, fast config (text, so the reader is exercised too).
std::string config_text(const std::string& dataset, const std::string& output, int epochs) {
  return "task: vae\n"
         "data: {dataset: " +
         dataset +
         ", validation_fraction: 0.2}\n"
         "model: {channels: [9, 8, 4, 1], hidden: 32, latent: 4, order: 2}\n"
         "loss: {kl_weight: 1.0e-4}\n"
         "optimiser: {lr: 1.0e-2}\n"
         "schedule: {decay: 0.6, every: 3}\n"
         "training: {epochs: " +
         std::to_string(epochs) +
         ", batch_size: 10, checkpoint_every: 1, seed: 7, threads: 1}\n"
         "output: " +
         output + "\n";
}

// `text` with its first `from` replaced by `to`.
std::string replaced_text(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

VaeTrainConfig config_for(const std::string& dataset, const std::string& output, int epochs) {
  return read_vae_train_config(ConfigNode::parse(config_text(dataset, output, epochs), "test.yaml"));
}

std::map<std::string, torch::Tensor> weights_of(const std::string& checkpoint, const VaeTrainConfig& config) {
  const Dataset d = load_dataset(config.data.dataset);
  MeshVae vae = build_mesh_vae(d.rest, config.model);
  load_vae_checkpoint(checkpoint, *vae, nullptr);
  std::map<std::string, torch::Tensor> out;
  for (const auto& p : vae->named_parameters()) out[p.key()] = p.value().clone();
  return out;
}

}  // namespace

TEST_CASE("a short VAE run lowers its loss and fills its run folder", "[vae_trainer]") {
  const fs::path out = scratch_dir("vae_trainer_short") / "run";
  const VaeTrainConfig config = config_for(avatar_dataset(), out.string(), 8);
  const VaeTrainSummary s = train_vae(config, quiet());
  CHECK(s.finished);
  CHECK(s.epochs_done == 8);
  CHECK(s.last_train_loss < 0.9 * s.first_train_loss);
  CHECK(s.validation_samples > 0);
  for (const char* file :
       {"config.yaml", "run.yaml", "metrics.jsonl", "metrics.csv", "checkpoints/last.pt", "checkpoints/best.pt"})
    CHECK(fs::exists(out / file));
  const auto metrics = read_metrics(out.string());
  REQUIRE(metrics.size() == 8);
  CHECK(metrics.front().at("epoch") == 1);
  CHECK(metrics.back().at("epoch") == 8);
  CHECK(metrics[3].at("lr") == Approx(1e-2 * 0.6));  // epoch 4: one decay step
  CHECK(std::isfinite(metrics.back().at("validation_l1")));
  const RunStatus status = RunStatus::load(out.string());
  CHECK(status.status == "finished");
  CHECK(status.best_epoch >= 1);
  CHECK(status.fingerprints.at("dataset") == load_dataset(avatar_dataset()).fingerprint);
  // The run's own config reads back to the same settings.
  CHECK(to_yaml(read_vae_train_config(ConfigNode::load_file((out / "config.yaml").string()))) == to_yaml(config));

  // The trained model reconstructs better than the untrained one, through the full mesh path.
  TrainedVae trained = load_trained_vae(out.string(), "best");
  const VaeEvaluation trained_eval = evaluate_vae(*trained.vae, trained.dataset);
  MeshVae untrained = build_mesh_vae(trained.dataset.rest, trained.config.model);
  const VaeEvaluation untrained_eval = evaluate_vae(*untrained, trained.dataset);
  CHECK(trained_eval.ground_truth == "rig meshes");
  CHECK(trained_eval.unit == "mm");
  CHECK(trained_eval.samples == static_cast<int64_t>(trained.dataset.test.size()));
  CHECK(trained_eval.mean < untrained_eval.mean);
  CHECK(trained_eval.max >= trained_eval.mean_of_max);
  CHECK(trained_eval.mean_of_max >= trained_eval.mean);
}

TEST_CASE("a squared-error run trains, logs its loss by name and keeps it in its config", "[vae_trainer]") {
  const fs::path out = scratch_dir("vae_trainer_squared") / "run";
  ConfigNode root = ConfigNode::parse(config_text(avatar_dataset(), out.string(), 4), "test.yaml");
  root.apply_override("loss.reconstruction=squared");
  const VaeTrainConfig config = read_vae_train_config(root);
  const VaeTrainSummary s = train_vae(config, quiet());
  CHECK(s.finished);
  CHECK(s.last_train_loss < s.first_train_loss);
  const VaeTrainConfig saved = read_vae_train_config(ConfigNode::load_file((out / "config.yaml").string()));
  CHECK(saved.reconstruction == ReconstructionLoss::squared);
  const auto metrics = read_metrics(out.string());
  REQUIRE(metrics.size() == 4);
  // The best epoch is still chosen by the validation L1, the measure the baselines are in.
  CHECK(std::isfinite(metrics.back().at("validation_l1")));
  CHECK(metrics.back().at("train_reconstruction") >= 0);
}

TEST_CASE("a decoder started at the principal components starts lower, and the run keeps the choice", "[vae_trainer]") {
  const fs::path dir = scratch_dir("vae_trainer_principal");
  VaeTrainSummary first[3];
  for (const int start : {0, 1, 2}) {  // random, principal, principal with the encoder skip
    const fs::path out = dir / (start == 0 ? "random" : start == 1 ? "principal" : "skip");
    ConfigNode root = ConfigNode::parse(config_text(avatar_dataset(), out.string(), 1), "test.yaml");
    root.apply_override("loss.reconstruction=squared");
    if (start > 0) root.apply_override("model.decoder_start=principal");
    if (start == 2) root.apply_override("model.encoder_skip=true");
    first[start] = train_vae(read_vae_train_config(root), quiet());
    const VaeTrainConfig saved = read_vae_train_config(ConfigNode::load_file((out / "config.yaml").string()));
    CHECK(saved.decoder_start == (start > 0 ? DecoderStart::principal : DecoderStart::random));
    CHECK(saved.model.encoder_skip() == (start == 2));
  }
  // The same seed, data and batches: the principal start's first epoch fits the rig better, and
  // with the encoder started at the principal codes better still.
  CHECK(first[1].first_train_loss < first[0].first_train_loss);
  CHECK(first[2].first_train_loss < first[1].first_train_loss);
}

TEST_CASE("a resumed run ends with the same weights as an uninterrupted one", "[vae_trainer]") {
  const fs::path dir = scratch_dir("vae_trainer_resume");
  const VaeTrainConfig straight = config_for(avatar_dataset(), (dir / "straight").string(), 5);
  train_vae(straight, quiet());

  const VaeTrainConfig interrupted = config_for(avatar_dataset(), (dir / "interrupted").string(), 5);
  const VaeTrainSummary first = train_vae(interrupted, quiet(RunStart::fresh, 2));
  CHECK_FALSE(first.finished);
  CHECK(first.epochs_done == 2);
  CHECK(RunStatus::load((dir / "interrupted").string()).status == "running");
  // As if the process died after logging epoch 3 but before its checkpoint.
  std::ofstream((dir / "interrupted" / "metrics.jsonl").string(), std::ios::app) << "{\"epoch\": 3, \"lr\": 1}\n{\"ep";

  CHECK_THROWS_WITH(train_vae(interrupted, quiet()),
                    Catch::Contains("unfinished run (epoch 2 of 5)") && Catch::Contains("--resume"));
  // The kill also cut a checkpoint write short: a temporary of a process that no longer runs
  // (no pid reaches 999999999: Linux's pid_max is at most 2^22).
  const fs::path stale = dir / "interrupted" / "checkpoints" / "last.pt.tmp.999999999.4";
  std::ofstream(stale.string()) << "half a checkpoint";
  const VaeTrainSummary second = train_vae(interrupted, quiet(RunStart::resume));
  CHECK_FALSE(fs::exists(stale));  // removed on resume
  CHECK(second.finished);
  CHECK(second.epochs_run == 3);

  const auto a = weights_of((dir / "straight" / "checkpoints" / "last.pt").string(), straight);
  const auto b = weights_of((dir / "interrupted" / "checkpoints" / "last.pt").string(), interrupted);
  REQUIRE(a.size() == b.size());
  for (const auto& [name, value] : a) {
    INFO(name);
    CHECK(torch::equal(value, b.at(name)));
  }
  const auto ma = read_metrics((dir / "straight").string());
  const auto mb = read_metrics((dir / "interrupted").string());
  REQUIRE(ma.size() == 5);
  REQUIRE(mb.size() == 5);
  for (size_t i = 0; i < ma.size(); ++i) CHECK(ma[i].at("train_loss") == mb[i].at("train_loss"));
  std::ifstream csv((dir / "interrupted" / "metrics.csv").string());
  int lines = 0;
  for (std::string line; std::getline(csv, line);) ++lines;
  CHECK(lines == 6);  // header + 5 epochs
}

TEST_CASE("a resumed run keeps a best checkpoint written after its last checkpoint", "[vae_trainer]") {
  const fs::path dir = scratch_dir("vae_trainer_newer_best");
  ConfigNode root = ConfigNode::parse(config_text(avatar_dataset(), (dir / "run").string(), 4), "test.yaml");
  root.apply_override("training.checkpoint_every=2");
  const VaeTrainConfig config = read_vae_train_config(root);
  train_vae(config, quiet(RunStart::fresh, 3));  // stopped after epoch 3: the last checkpoint is epoch 2's
  REQUIRE(RunStatus::load(config.output).epochs_done == 2);
  // best.pt as if epoch 3 had scored better than any epoch will (its weights: the VAE's own).
  const std::string best = (dir / "run" / "checkpoints" / "best.pt").string();
  const Dataset d = load_dataset(config.data.dataset);
  MeshVae vae = build_mesh_vae(d.rest, config.model);
  load_vae_checkpoint(best, *vae, nullptr);
  save_vae_checkpoint(best, *vae, nullptr, {3, 3, 1e-9});

  const VaeTrainSummary resumed = train_vae(config, quiet(RunStart::resume));
  CHECK(resumed.finished);
  CHECK(resumed.best_epoch == 3);
  CHECK(resumed.best_validation == 1e-9);
  const RunStatus status = RunStatus::load(config.output);
  CHECK(status.best_epoch == 3);
  CHECK(status.best_validation == Approx(1e-9));
  CHECK(read_checkpoint_state(best).best_validation == 1e-9);  // not replaced by a worse epoch
}

TEST_CASE("finished runs are not overwritten unless forced", "[vae_trainer]") {
  const fs::path out = scratch_dir("vae_trainer_overwrite") / "run";
  const VaeTrainConfig config = config_for(avatar_dataset(), out.string(), 1);
  train_vae(config, quiet());
  CHECK_THROWS_WITH(train_vae(config, quiet()), Catch::Contains("finished run") && Catch::Contains("--force"));
  CHECK_THROWS_WITH(train_vae(config, quiet(RunStart::resume)), Catch::Contains("nothing to resume"));
  const VaeTrainSummary again = train_vae(config, quiet(RunStart::force));
  CHECK(again.finished);
  CHECK(read_metrics(out.string()).size() == 1);
  CHECK_THROWS_WITH(
      train_vae(config_for(avatar_dataset(), (out.parent_path() / "none").string(), 1), quiet(RunStart::resume)),
      Catch::Contains("no run to resume"));
}

TEST_CASE("the human VAE maps people's expressions towards the identity-averaged ones", "[vae_trainer]") {
  const fs::path out = scratch_dir("vae_trainer_human") / "run";
  const VaeTrainConfig config = config_for(human_dataset(), out.string(), 10);
  const VaeTrainSummary s = train_vae(config, quiet());
  CHECK(s.finished);
  CHECK(s.last_train_loss < s.first_train_loss);
  TrainedVae trained = load_trained_vae(out.string(), "last");
  const VaeEvaluation e = evaluate_vae(*trained.vae, trained.dataset);
  CHECK(e.ground_truth.find("identity-averaged") != std::string::npos);
  CHECK(std::isfinite(e.code_distance_ratio));
  CHECK(e.code_distance_ratio > 0);
  CHECK(e.within_expression < e.between_expression);
}

TEST_CASE("bad training configs fail before any work, naming the key path", "[vae_trainer]") {
  const std::string good = config_text("data", "out", 2);
  auto parse = [](const std::string& text) { return read_vae_train_config(ConfigNode::parse(text, "c.yaml")); };
  CHECK_NOTHROW(parse(good));
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string text = good;
    const size_t at = text.find(from);
    REQUIRE(at != std::string::npos);
    return text.replace(at, from.size(), to);
  };
  CHECK(error_of([&] { parse(replaced("latent: 4", "laten: 4")); }) ==
        "c.yaml:3: model.laten: unknown key (did you mean 'latent'?)");
  CHECK_THROWS_WITH(parse(replaced("epochs: 2", "epochs: fast")),
                    Catch::Contains("training.epochs") && Catch::Contains("fast"));
  CHECK_THROWS_WITH(parse(replaced("lr: 1.0e-2", "lr: -1")), Catch::Contains("optimiser.lr"));
  CHECK_THROWS_WITH(parse(replaced("decay: 0.6", "decay: 1.5")), Catch::Contains("schedule.decay"));
  CHECK_THROWS_WITH(parse(replaced("channels: [9, 8, 4, 1]", "channels: [3, 8, 4, 1]")),
                    Catch::Contains("model.channels[0]") && Catch::Contains("expected 9"));
  CHECK_THROWS_WITH(parse(replaced("task: vae", "task: gan")), Catch::Contains("task") && Catch::Contains("gan"));
  CHECK(error_of([&] { parse(replaced("output: out\n", "")); }) ==
        "c.yaml: output: missing: the run folder; give it with `retarget train CONFIG --out DIR` (or --set "
        "output=DIR)");
  CHECK(error_of([&] { parse(replaced("kl_weight: 1.0e-4", "kl_weight: 1.0e-4, reconstruction: l2")); }) ==
        "c.yaml:4: loss.reconstruction: expected 'l1' or 'squared', got 'l2'");
  CHECK(parse(replaced("kl_weight: 1.0e-4", "kl_weight: 1.0e-4, reconstruction: squared")).reconstruction ==
        ReconstructionLoss::squared);
  CHECK(parse(good).reconstruction == ReconstructionLoss::l1);
  // latent: auto sizes the code by the avatar dataset's controllers (read from its manifest).
  const fs::path many = scratch_dir("vae_config_auto_latent");
  std::string names;
  for (int c = 0; c < 40; ++c) names += (c ? ", c" : "c") + std::to_string(c);
  std::ofstream(many / "manifest.yaml") << "format: 1\nkind: avatar\ncontrollers: [" << names << "]\n";
  const std::string auto_text = replaced("latent: 4", "latent: auto");
  const auto with_dataset = [&](const std::string& dataset) {
    ConfigNode root = ConfigNode::parse(auto_text, "c.yaml");
    root.apply_override("data.dataset=" + dataset);
    return read_vae_train_config(root);
  };
  CHECK(with_dataset(many.string()).model.latent() == 40);
  CHECK(with_dataset(avatar_dataset()).model.latent() == kPaperLatent);  // 4 controllers: the paper's 25
  CHECK(read_vae_train_config(ConfigNode::parse(to_yaml(with_dataset(many.string())), "again.yaml")).model.latent() ==
        40);
  CHECK_THROWS_WITH(with_dataset((many / "missing").string()),
                    Catch::Contains("c.yaml:3: model.latent: 'auto' sizes the latent by the dataset's controllers") &&
                        Catch::Contains("dataset folder not found"));
  CHECK(parse(good).decoder_start == DecoderStart::random);
  CHECK(parse(replaced("order: 2", "order: 2, decoder_start: principal")).decoder_start == DecoderStart::principal);
  CHECK(error_of([&] { parse(replaced("order: 2", "order: 2, decoder_start: pca")); }) ==
        "c.yaml:3: model.decoder_start: expected 'random' or 'principal', got 'pca'");
  CHECK_FALSE(parse(good).model.encoder_skip());
  const VaeTrainConfig skip = parse(replaced("order: 2", "order: 2, decoder_start: principal, encoder_skip: true"));
  CHECK(skip.model.encoder_skip());
  CHECK(read_vae_train_config(ConfigNode::parse(to_yaml(skip), "again.yaml")).model.encoder_skip());
  CHECK_THROWS_WITH(parse(replaced("order: 2", "order: 2, encoder_skip: true")),
                    Catch::Contains("c.yaml:3: model.encoder_skip: needs model.decoder_start: principal"));
  CHECK_THROWS_WITH(parse(replaced("order: 2", "order: 2, decoder_start: principal, encoder_skip: maybe")),
                    Catch::Contains("model.encoder_skip"));
  // Widths are bounded before anything is allocated (2^31 was LibTorch's allocation error,
  // escaping main).
  CHECK_THROWS_WITH(
      parse(replaced("channels: [9, 8, 4, 1]", "channels: [9, 2147483648, 4, 1]")),
      Catch::Contains("c.yaml") && Catch::Contains("model.channels[1]: expected at most 65536, got 2147483648"));
  CHECK_NOTHROW(parse(replaced("hidden: 32", "hidden: 65536")));
  CHECK_THROWS_WITH(parse(replaced("hidden: 32", "hidden: 65537")),
                    Catch::Contains("model.hidden: expected at most 65536"));
  CHECK_THROWS_WITH(parse(replaced("channels: [9, 8, 4, 1]", "channels: [9, 65536, 65536, 1]")),
                    Catch::Contains("c.yaml") && Catch::Contains("model: these widths make a model of") &&
                        Catch::Contains("GiB) before any vertex is counted (for a 1-vertex mesh); the bound") &&
                        Catch::Contains("use narrower layers"));

  ConfigNode root = ConfigNode::parse(good, "c.yaml");
  root.apply_override("training.epochs=7");
  root.apply_override("model.channels=[9, 16, 1]");
  const VaeTrainConfig overridden = read_vae_train_config(root);
  CHECK(overridden.training.epochs == 7);
  CHECK(overridden.model.channels() == std::vector<int64_t>{9, 16, 1});
  ConfigNode bad = ConfigNode::parse(good, "c.yaml");
  bad.apply_override("training.batch_size=many");
  CHECK_THROWS_WITH(read_vae_train_config(bad), Catch::Contains("training.batch_size"));
  CHECK_THROWS_WITH(bad.apply_override("training.epochs"),
                    Catch::Contains("--set training.epochs") && Catch::Contains("key.path=value"));
  CHECK_THROWS_WITH(bad.apply_override("output.x=1"), Catch::Contains("'output' is not a map"));
}

TEST_CASE("a config built on a base: bad values are named with the file and line they came from", "[vae_trainer]") {
  const fs::path dir = scratch_dir("vae_config_base");
  const std::string base =
      write_file(dir, "base.yaml", replaced_text(config_text("data", "out", 2), "decay: 0.6", "decay: 1.5"));
  const std::string overlay =
      write_file(dir, "overlay.yaml", "base: base.yaml\nschedule: {every: 4}\ntraining:\n  batch_size: 0\n");
  // A value taken from the base, in a section the overlay also has: the base's file and line.
  CHECK(error_of([&] { read_vae_train_config(load_config_with_overrides(overlay, {"training.batch_size=5"})); }) ==
        base + ":6: schedule.decay: expected a number in (0, 1], got 1.5");
  // The overlay's own value: its file and line; a --set value: the --set.
  CHECK(error_of([&] { read_vae_train_config(load_config_with_overrides(overlay, {"schedule.decay=0.5"})); }) ==
        overlay + ":4: training.batch_size: expected a positive number, got 0");
  CHECK(error_of([&] {
          read_vae_train_config(load_config_with_overrides(overlay, {"schedule.decay=2", "training.batch_size=5"}));
        }) == "--set schedule.decay=2: schedule.decay: expected a number in (0, 1], got 2");
  const VaeTrainConfig merged =
      read_vae_train_config(load_config_with_overrides(overlay, {"schedule.decay=0.5", "training.batch_size=5"}));
  CHECK(merged.schedule.every == 4);
  CHECK(merged.training.epochs == 2);
  CHECK(merged.model.channels() == std::vector<int64_t>{9, 8, 4, 1});
  CHECK(merged.source == overlay);
}

TEST_CASE("a dataset that is not there is named with the config's file, line and key", "[vae_trainer]") {
  const fs::path dir = scratch_dir("vae_trainer_no_dataset");
  const std::string text = config_text(".nan", (dir / "run").string(), 1);
  const VaeTrainConfig config = read_vae_train_config(ConfigNode::parse(text, "c.yaml"));
  CHECK(error_of([&] { train_vae(config, quiet()); }) == "c.yaml:2: data.dataset: .nan: dataset folder not found");
}

TEST_CASE("retarget train: model widths too large for memory are an error, not an abort", "[vae_trainer][cli]") {
  const fs::path dir = scratch_dir("vae_trainer_cli_widths");
  const fs::path config = dir / "c.yaml";
  std::ofstream(config) << config_text(avatar_dataset(), (dir / "run").string(), 1);
  // `retarget train c.yaml --set ...` in-process; returns the exit status, its stderr in `err`.
  auto train = [&](std::vector<std::string> sets, std::string& err) {
    std::vector<std::string> args = {"retarget", "train", config.string(), "--force"};
    for (const std::string& set : sets) args.insert(args.end(), {"--set", set});
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    std::ostringstream captured;
    std::streambuf* const saved = std::cerr.rdbuf(captured.rdbuf());
    const int status = cli::run(static_cast<int>(argv.size()), argv.data());
    std::cerr.rdbuf(saved);
    err = captured.str();
    return status;
  };
  std::string err;
  CHECK(train({"model.channels=[9, 2147483648, 16, 16, 16, 1]"}, err) == 1);
  CHECK_THAT(err, Catch::Contains("retarget train:") && Catch::Contains("model.channels[1]") &&
                      Catch::Contains("expected at most 65536, got 2147483648"));
  // A model too large for this dataset's vertex count, found once the dataset is read.
  CHECK(train({"model.channels=[9, 8, 4, 1000]", "model.hidden=20000"}, err) == 1);
  CHECK_THAT(err, Catch::Contains("c.yaml: model: these widths make a model of") &&
                      Catch::Contains("with the dataset's 64 vertices"));
}

TEST_CASE("a checkpoint does not load into another architecture", "[vae_trainer]") {
  const fs::path out = scratch_dir("vae_trainer_arch") / "run";
  const VaeTrainConfig config = config_for(avatar_dataset(), out.string(), 1);
  train_vae(config, quiet());
  const Dataset d = load_dataset(avatar_dataset());
  MeshVaeOptions other = config.model;
  other.hidden(16);
  MeshVae vae = build_mesh_vae(d.rest, other);
  CHECK_THROWS_WITH(load_vae_checkpoint((out / "checkpoints" / "last.pt").string(), *vae, nullptr),
                    Catch::Contains("encoder_hidden.weight") && Catch::Contains("[32, 64]"));
  CHECK_THROWS_WITH(load_vae_checkpoint((out / "checkpoints" / "none.pt").string(), *vae, nullptr),
                    Catch::Contains("no such checkpoint"));
}

TEST_CASE("a trained run exports TorchScript that reproduces it and checks the topology", "[vae_trainer]") {
  const fs::path dir = scratch_dir("vae_trainer_export");
  const VaeTrainConfig config = config_for(avatar_dataset(), (dir / "run").string(), 2);
  train_vae(config, quiet());
  TrainedVae trained = load_trained_vae((dir / "run").string(), "best");
  const VaeExportMetadata metadata = export_trained_vae(trained, (dir / "export").string());
  CHECK(metadata.kind == "avatar");
  CHECK(metadata.vertices == 64);

  // Plain torch::jit::load, raw DR features in, raw DR features out.
  torch::jit::Module encoder = torch::jit::load((dir / "export" / "encoder.pt").string());
  torch::jit::Module decoder = torch::jit::load((dir / "export" / "decoder.pt").string());
  const Dataset& d = trained.dataset;
  const torch::Tensor raw = d.features.index_select(0, torch::tensor(d.test)).to(torch::kFloat32);
  torch::NoGradGuard no_grad;
  const VaeEncoding code = trained.vae->encode(d.normaliser.normalise(raw));
  const torch::Tensor mean = encoder.forward({raw}).toTensor();
  CHECK((mean - code.mean).abs().max().item<double>() < 1e-5);
  const torch::Tensor decoded = decoder.forward({mean}).toTensor();
  const torch::Tensor expected = d.normaliser.denormalise(trained.vae->decode(code.mean));
  CHECK((decoded - expected).abs().max().item<double>() < 1e-5);

  // A loader that knows its mesh refuses an export for another topology.
  CHECK_NOTHROW(load_exported_vae((dir / "export").string(), {64, d.fingerprint}));
  CHECK_THROWS_WITH(load_exported_vae((dir / "export").string(), {36, ""}),
                    Catch::Contains("64") && Catch::Contains("36"));
  const Dataset other = load_dataset(human_dataset());
  CHECK_THROWS_WITH(load_exported_vae((dir / "export").string(), {std::nullopt, other.fingerprint}),
                    Catch::Contains(other.fingerprint) && Catch::Contains(d.fingerprint));
}

TEST_CASE("retarget train: --set values keep their commas (YAML lists), in either spelling", "[vae_trainer][cli]") {
  const fs::path dir = scratch_dir("vae_trainer_cli");
  const fs::path config = dir / "config.yaml";
  {
    std::ofstream out(config);
    out << config_text(avatar_dataset(), (dir / "ignored").string(), 1);
  }
  const std::string output = (dir / "run").string();
  std::vector<std::string> args = {
      "train", config.string(),    "--set", "model.channels=[9, 6, 3, 1]", "--set=output=" + output,
      "--set", "training.epochs=2"};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  CHECK(cli::train_command(static_cast<int>(argv.size()), argv.data()) == 0);
  const VaeTrainConfig written =
      read_vae_train_config(load_config_with_overrides((fs::path(output) / "config.yaml").string(), {}));
  CHECK(written.model.channels() == std::vector<int64_t>{9, 6, 3, 1});
  CHECK(written.training.epochs == 2);
  CHECK(fs::exists(fs::path(output) / "checkpoints/last.pt"));

  std::vector<std::string> dangling = {"train", config.string(), "--set"};
  std::vector<char*> dangling_argv;
  for (std::string& a : dangling) dangling_argv.push_back(a.data());
  CHECK(error_of([&] { cli::train_command(static_cast<int>(dangling_argv.size()), dangling_argv.data()); }) ==
        "retarget train: --set needs a value: --set key.path=value");
}
