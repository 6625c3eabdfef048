// `retarget eval ladder --correspondences C --translation RUN [--checkpoint last|stageN] [--table T]
// [--out DIR]`: where the end-to-end error comes from (eval/error_ladder.h).
#include <fmt/format.h>

#include <cxxopts.hpp>
#include <iostream>

#include "cli/command_options.h"
#include "cli/commands.h"
#include "core/error.h"
#include "core/progress.h"
#include "eval/error_ladder.h"

namespace retarget::cli {

int eval_ladder(int argc, char** argv) {
  cxxopts::Options options(
      "retarget eval ladder",
      "Where the end-to-end error comes from: each part of the chain (avatar VAE on held-out rig samples and\n"
      "on the ground-truth expressions, human VAE on unseen people, deformation transfer, y0 through the\n"
      "decoder, F on training and unseen people) scored against the rig's ground truth beside the neutral\n"
      "answer, in mm (eye distance 10 cm) and as a fraction of it. Writes DIR/ladder.json.");
  ErrorLadderOptions ladder;
  options.add_options()("correspondences", "the correspondence folder", cxxopts::value<std::string>())(
      "translation", "the translation run folder", cxxopts::value<std::string>())(
      "checkpoint", "F's checkpoint: last or stage<N>", cxxopts::value<std::string>()->default_value("last"))(
      "table", "controller table (default: correspondence.yaml beside the rig)", cxxopts::value<std::string>())(
      "out", "output folder (default: RUN/ladder)", cxxopts::value<std::string>())(
      "faces",
      "a folder written by `retarget faces --blends N`: adds rungs 9 and 10, F on its unseen blends and their truth "
      "through the avatar VAE",
      cxxopts::value<std::string>())("batch", "samples per network batch",
                                     cxxopts::value<int64_t>()->default_value("64"))(
      "no-anchors", "let the avatar's still vertices move when rebuilding its meshes")(
      "no-part-motion", "keep the avatar's rigid parts at rest instead of moving them with its rig");
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  if (args.count("correspondences")) ladder.correspondences = args["correspondences"].as<std::string>();
  if (args.count("translation")) ladder.translation = args["translation"].as<std::string>();
  if (args.count("table")) ladder.table = args["table"].as<std::string>();
  if (args.count("out")) ladder.out = args["out"].as<std::string>();
  if (args.count("faces")) ladder.faces = args["faces"].as<std::string>();
  ladder.checkpoint = args["checkpoint"].as<std::string>();
  ladder.batch = args["batch"].as<int64_t>();
  ladder.anchors = args.count("no-anchors") == 0;
  ladder.part_motion = args.count("no-part-motion") == 0;
  const ErrorLadder r = error_ladder(ladder);
  std::cout << fmt::format("{} ({} checkpoint, epoch {}) with {}\n", r.translation, r.checkpoint, r.translation_epoch,
                           r.correspondences)
            << ladder_table(r) << fmt::format("  written: {} ({})\n", r.json_path, format_duration(r.seconds));
  return 0;
}

}  // namespace retarget::cli
