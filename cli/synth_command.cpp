// `retarget synth --out DIR [--seed N] [--force]`: writes the bundled synthetic human face
// model and avatars (synthetic/synthetic_faces.h) in the formats users bring.
#include <fmt/format.h>

#include <cxxopts.hpp>
#include <iostream>

#include "cli/command_options.h"
#include "cli/commands.h"
#include "cli/output_folder.h"
#include "core/error.h"
#include "core/timer.h"
#include "synthetic/synthetic_faces.h"

namespace retarget::cli {

int synth_command(int argc, char** argv) {
  cxxopts::Options options("retarget synth",
                           "Write the bundled synthetic default: a human face model (DIR/human/face_model.yaml) and\n"
                           "stylized avatar rigs with their controller correspondences (DIR/avatars/<name>/), plus\n"
                           "DIR/README.txt. Deterministic for a seed; the seed changes the human's mean face.");
  options.add_options()("out", "output folder", cxxopts::value<std::string>())(
      "seed", "random seed", cxxopts::value<uint64_t>()->default_value("1"))(
      "force", "write into a non-empty folder (files of the same names are replaced)");
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  if (!args.count("out")) throw Error("retarget synth", "missing --out DIR (see --help)");
  const std::string out = args["out"].as<std::string>();
  check_output_folder(out, args.count("force") > 0);

  Stopwatch clock;
  const SyntheticSet set = synthetic_set(args["seed"].as<uint64_t>());
  const double build_seconds = clock.restart();
  write_synthetic_set(out, set);
  const double write_seconds = clock.seconds();

  const FaceModel& h = set.human;
  std::cout << fmt::format("human  {:<8} {:>6} vertices  {:>3} identity modes  {:>3} expressions  {:>3} landmarks\n",
                           "", h.neutral.vertex_count(), h.identities.size(), h.expressions.size(), h.landmarks.size());
  for (const SyntheticAvatar& a : set.avatars) {
    int counterparts = 0;
    for (const auto& row : a.correspondence) counterparts += !row.second.empty();
    std::cout << fmt::format(
        "avatar {:<8} {:>6} vertices  {:>3} controllers ({} with a human counterpart)  {:>3} landmarks\n", a.rig.name,
        a.rig.neutral.vertex_count(), a.rig.controller_count(), counterparts, a.rig.landmarks.size());
  }
  std::cout << fmt::format("built in {:.2f} s, written in {:.2f} s to {} (see {}/README.txt)\n", build_seconds,
                           write_seconds, out, out);
  return 0;
}

}  // namespace retarget::cli
