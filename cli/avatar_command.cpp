// `retarget avatar init|meaning|landmarks`: a new avatar made ready from its rig alone.
#include <cxxopts.hpp>
#include <iostream>

#include "avatar/avatar_init.h"
#include "avatar/landmark_proposals.h"
#include "cli/command_options.h"
#include "cli/commands.h"
#include "cli/mesh_size_options.h"
#include "cli/output_folder.h"
#include "core/error.h"
#include "core/log.h"
#include "core/timer.h"
#include "geometry/metrics.h"
#include "geometry/rig.h"

namespace retarget::cli {

int avatar_init(int argc, char** argv) {
  cxxopts::Options options(
      "retarget avatar init",
      "Propose everything a new avatar needs from its rig alone, and write a complete rig folder:\n"
      "rig.yaml with the proposed landmarks (mouth corners, lip centres, eye corners and lids, nose tip)\n"
      "and eyes, each landmark's confidence and origin as a comment, the mirror plane, the face's axes,\n"
      "the scale and the parts; the meshes (never welded); proposals.yaml; landmarks.png (front and side\n"
      "views, every proposal marked). RIG: a rig folder or rig.yaml, or a .gltf/.glb file.");
  options.add_options()("rig", "the avatar's rig", cxxopts::value<std::string>())("out", "the folder to write",
                                                                                  cxxopts::value<std::string>())(
      "mesh", "glTF only: the mesh whose morph targets are the controllers", cxxopts::value<std::string>())(
      "compare",
      "a rig of the same mesh with hand-picked landmarks: report how far each proposal lies from the landmark of "
      "the same name, in % of the eye distance",
      cxxopts::value<std::string>())("force", "write into a non-empty folder")(
      "h,help", "show this help");  // before the mesh size options, as its help has always listed it
  add_mesh_size_options(options);
  options.parse_positional({"rig"});
  options.positional_help("RIG --out DIR");
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  if (!args.count("rig"))
    throw Error("retarget avatar init", "missing the rig (a folder, rig.yaml or .glb; see --help)");
  if (!args.count("out")) throw Error("retarget avatar init", "missing --out DIR (see --help)");
  const std::string out = args["out"].as<std::string>();
  check_output_folder(out, args.count("force") > 0);
  const MeshSizeLimits size = mesh_size_limits(args);

  Stopwatch clock;
  const Rig rig = load_rig(args["rig"].as<std::string>(), args.count("mesh") ? args["mesh"].as<std::string>() : "");
  check_mesh_size(rig.neutral, size, args["rig"].as<std::string>());
  const LandmarkProposal proposal = propose_landmarks(rig);
  const double seconds = clock.restart();
  write_avatar_folder(out, rig, proposal);
  std::cout << fmt::format("{}: {} vertices, {} controllers; proposed in {:.2f} s, written to {} in {:.2f} s\n",
                           rig.source, rig.neutral.vertex_count(), rig.controller_count(), seconds, out,
                           clock.seconds());
  for (const std::string& note : proposal.notes) std::cout << "  " << note << "\n";
  std::map<std::string, double> distances;
  if (args.count("compare")) distances = landmark_distances(load_rig(args["compare"].as<std::string>()), proposal);
  for (const auto& [name, landmark] : proposal.landmarks) {
    std::cout << fmt::format("  {:<20} vertex {:>6}  confidence {:.2f}", name, landmark.vertex, landmark.confidence);
    const auto it = distances.find(name);
    if (it != distances.end())
      std::cout << fmt::format("  {:5.2f}% of the eye distance from the reference", 100 * it->second);
    std::cout << "\n";
  }
  for (const ProposedPart& part : proposal.parts)
    std::cout << fmt::format("  part {:<12} {:<6} {} vertices\n", part.name, part_kind_name(part.kind),
                             part.vertices.size());
  std::cout << fmt::format("check {}/landmarks.png, then use {}/rig.yaml\n", out, out);
  return 0;
}

int avatar_command(int argc, char** argv) {
  const std::string usage =
      "usage: retarget avatar init RIG --out DIR    propose landmarks, eyes and parts; write a rig folder\n"
      "       retarget avatar meaning --rig RIG --face-model F --out correspondence.yaml    what each controller "
      "means\n"
      "       retarget avatar landmarks RIG_FOLDER --face-model FACE_MODEL_YAML    correct them in the browser\n";
  if (argc < 2) throw Error("retarget avatar", "missing the subcommand\n" + usage);
  const std::string sub = argv[1];
  if (sub == "init") return avatar_init(argc - 1, argv + 1);
  if (sub == "meaning") return avatar_meaning(argc - 1, argv + 1);
  if (sub == "landmarks") return avatar_landmarks(argc - 1, argv + 1);
  if (sub == "-h" || sub == "--help") {
    std::cout << usage;
    return 0;
  }
  throw Error("retarget avatar", "unknown subcommand \"" + sub + "\"\n" + usage);
}

}  // namespace retarget::cli
