// `retarget export RUN [--out DIR] [--checkpoint ...]`: a VAE run as TorchScript encoder and
// decoder, a translation run as the retargeting bundle (export/bundle_export.h).
#include <fmt/format.h>

#include <cxxopts.hpp>
#include <filesystem>
#include <iostream>

#include "cli/command_options.h"
#include "cli/commands.h"
#include "core/error.h"
#include "export/bundle_export.h"
#include "export/vae_export.h"
#include "train/run_folder.h"
#include "train/vae_run.h"
#include "translate/cyclegan_run.h"
#include "translate/linear_expression_cloning.h"
#include "translate/translation_data.h"
#include "translate/translation_run.h"

namespace retarget::cli {

namespace fs = std::filesystem;

namespace {

// The LEC bundle of a translation run: the map fitted to the run's own pairs, with its VAEs.
int export_lec(const std::string& run, const std::string& out, double ridge) {
  const TrainedTranslation trained = load_trained_translation(run, "last");
  const TranslationData data = load_translation_data(trained.config.data, trained.config.training.seed);
  const torch::Tensor targets = data.y0.index_select(0, data.input_expression);
  LecOptions options;
  options.ridge = ridge;
  BundleParts parts = translation_bundle_parts(trained);
  parts.translation = fit_linear_expression_cloning(data.inputs, targets, options);
  torch::NoGradGuard no_grad;
  const double residual = (parts.translation->forward(data.inputs) - targets).pow(2).sum(1).mean().item<double>();
  const double spread = (targets - targets.mean(0)).pow(2).sum(1).mean().item<double>();
  export_bundle(parts, out);
  std::cout << fmt::format(
      "{} -> {}: linear expression cloning fitted to {} pairs of {} expressions (human codes -> y0), "
      "mean squared residual {:.4g} code units (x{:.3f} of the targets' spread)\n  next: retarget-infer --bundle {} "
      "...\n",
      run, out, data.inputs.size(0), data.expressions.size(), residual, spread > 0 ? residual / spread : 0.0, out);
  return 0;
}

// The bundle of a CycleGAN+LFD run: its generator from human to avatar codes between its VAEs.
int export_cyclegan(const std::string& run, const std::string& out) {
  const TrainedCycleGan trained = load_trained_cyclegan(run);
  export_bundle(cyclegan_bundle_parts(trained), out);
  std::cout << fmt::format(
      "{} (CycleGAN+LFD after epoch {}) -> {}: the generator from human to avatar codes\n"
      "  next: retarget-infer --bundle {} ...\n",
      run, trained.state.epoch, out, out);
  return 0;
}

}  // namespace

int export_command(int argc, char** argv) {
  cxxopts::Options options(
      "retarget export",
      "Exports a trained run.\n"
      "  A VAE run: TorchScript DIR/encoder.pt (raw DR features [B, V, 9] -> code means [B, latent]) and\n"
      "  DIR/decoder.pt (codes -> raw DR features), with the normaliser and metadata inside; loadable by\n"
      "  torch::jit::load and Python's torch.jit.load. Default DIR: RUN/export.\n"
      "  A translation run: the retargeting bundle for retarget-infer (DIR/bundle.pt: raw human DR\n"
      "  features -> human encoder -> F -> avatar decoder -> raw avatar DR features; manifest.yaml and\n"
      "  both rest meshes; rig.pt, the avatar dataset's rig, for retarget-infer --weights). Default DIR: RUN/bundle.\n"
      "  A CycleGAN run (the CycleGAN+LFD baseline): the same bundle with its human-to-avatar generator.");
  options.add_options()("run", "run folder", cxxopts::value<std::string>())("out", "output folder",
                                                                            cxxopts::value<std::string>())(
      "checkpoint", "VAE runs: best (default) or last; translation runs: last (default) or stage1, stage2, ...",
      cxxopts::value<std::string>())(
      "lec",
      "translation runs: the bundle of linear expression cloning instead of F (the paper's eq. 9 baseline: one "
      "linear map fitted to the pairs F's paired loss learns; default DIR: RUN/bundle-lec)")(
      "lec-ridge", "with --lec: ridge as a fraction of the codes' variance",
      cxxopts::value<double>()->default_value("1e-4"));
  options.parse_positional({"run"});
  options.positional_help("RUN");
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  if (!args.count("run")) throw Error("retarget export", "expected a run folder (see --help)");
  const std::string run = args["run"].as<std::string>();
  const std::string task = RunStatus::load(run).task;
  auto out_or = [&](const char* name) {
    return args.count("out") ? args["out"].as<std::string>() : (fs::path(run) / name).string();
  };
  if (args.count("lec")) {
    if (task != "translation") throw Error("--lec", run + " is a '" + task + "' run; LEC needs a translation run");
    return export_lec(run, out_or("bundle-lec"), args["lec-ridge"].as<double>());
  }
  if (task == "translation") {
    const std::string which = args.count("checkpoint") ? args["checkpoint"].as<std::string>() : "last";
    const std::string out = out_or("bundle");
    const TrainedTranslation trained = load_trained_translation(run, which);
    export_bundle(translation_bundle_parts(trained), out);
    const LoadedBundle bundle = load_bundle(out);
    const BundleMetadata& m = bundle.metadata;
    const std::string rig =
        m.rig ? fmt::format("rig: {} controllers (retarget-infer --weights)", m.rig->controllers.size())
              : std::string("no rig (the avatar dataset's rig did not load; no --weights)");
    std::cout << fmt::format(
        "{} (translation, {} checkpoint after epoch {}) -> {}: human '{}' ({} vertices, latent {}) -> avatar '{}' ({} "
        "vertices, latent {}), {}\n  next: retarget-infer --bundle {} ...\n",
        run, which, trained.state.epoch, out, m.human.name, m.human.vertices, m.human.latent, m.avatar.name,
        m.avatar.vertices, m.avatar.latent, rig, out);
    return 0;
  }
  if (task == "cyclegan") return export_cyclegan(run, out_or("bundle"));
  if (task != "vae") throw Error(run, "is a '" + task + "' run; only vae, translation and cyclegan runs export");
  const std::string which = args.count("checkpoint") ? args["checkpoint"].as<std::string>() : "best";
  const std::string out = out_or("export");
  TrainedVae trained = load_trained_vae(run, which);
  const VaeExportMetadata metadata = export_trained_vae(trained, out);
  std::cout << fmt::format(
      "{} ({} VAE '{}', {} vertices, latent {}, {} checkpoint of epoch {}) -> {}/encoder.pt, "
      "{}/decoder.pt\n",
      run, metadata.kind, metadata.name, metadata.vertices, metadata.latent, which, trained.state.epoch, out, out);
  return 0;
}

}  // namespace retarget::cli
