// `retarget export RUN --out DIR [--checkpoint best|last]`
#include <fmt/format.h>

#include <cxxopts.hpp>
#include <filesystem>
#include <iostream>

#include "core/error.h"
#include "models/vae_export.h"
#include "train/commands.h"
#include "train/vae_run.h"

namespace retarget::cli {

namespace fs = std::filesystem;

int export_command(int argc, char** argv) {
  cxxopts::Options options("retarget export",
                           "Writes a trained VAE as TorchScript: DIR/encoder.pt (raw DR features [B, V, 9] -> code\n"
                           "means [B, latent]) and DIR/decoder.pt (codes -> raw DR features), with the normaliser\n"
                           "and metadata inside; loadable by torch::jit::load and Python's torch.jit.load.");
  options.add_options()("run", "run folder", cxxopts::value<std::string>())(
      "out", "output folder (default: RUN/export)", cxxopts::value<std::string>())(
      "checkpoint", "best or last", cxxopts::value<std::string>()->default_value("best"))("h,help", "show this help");
  options.parse_positional({"run"});
  options.positional_help("RUN");
  const cxxopts::ParseResult args = options.parse(argc, argv);
  if (args.count("help")) {
    std::cout << options.help() << "\n";
    return 0;
  }
  if (!args.count("run")) throw Error("retarget export", "expected a run folder (see --help)");
  const std::string run = args["run"].as<std::string>();
  const std::string out = args.count("out") ? args["out"].as<std::string>() : (fs::path(run) / "export").string();
  const std::string which = args["checkpoint"].as<std::string>();
  TrainedVae trained = load_trained_vae(run, which);
  const VaeExportMetadata metadata = export_trained_vae(trained, out);
  std::cout << fmt::format(
      "{} ({} VAE '{}', {} vertices, latent {}, {} checkpoint of epoch {}) -> {}/encoder.pt, "
      "{}/decoder.pt\n",
      run, metadata.kind, metadata.name, metadata.vertices, metadata.latent, which, trained.state.epoch, out, out);
  return 0;
}

}  // namespace retarget::cli
