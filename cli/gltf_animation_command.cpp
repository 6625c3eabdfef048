// `retarget gltf-animation (--rig RIG | --bundle B) --weights weights.csv --out anim.glb
// [--fps 30]`: a controller-weight sequence (retarget-infer --weights) as a glTF 2.0 morph-target
// animation on the rig's neutral mesh, for engines (infer/gltf_animation.h).
#include <fmt/format.h>

#include <cctype>
#include <cxxopts.hpp>
#include <filesystem>
#include <iostream>

#include "bundle/bundle_format.h"
#include "cli/command_options.h"
#include "cli/commands.h"
#include "core/error.h"
#include "geometry/rig.h"
#include "infer/gltf_animation.h"
#include "infer/weights_csv.h"

namespace retarget::cli {

int gltf_animation_command(int argc, char** argv) {
  cxxopts::Options options(
      "retarget gltf-animation",
      "Write controller weights per frame (weights.csv from retarget-infer --weights) as a glTF 2.0\n"
      "animation: the rig's neutral mesh with one morph target per controller, and the weights over\n"
      "time (LINEAR). .glb writes binary glTF, .gltf JSON with the buffer embedded. The CSV's columns\n"
      "must be the rig's controllers, in its order: --bundle takes the rig the bundle carries, the one\n"
      "retarget-infer --weights solved against.");
  options.add_options()("rig", "the avatar rig: a folder with rig.yaml, or a .gltf/.glb file",
                        cxxopts::value<std::string>())(
      "bundle", "instead of --rig: a retargeting bundle that carries its avatar's rig (format 3)",
      cxxopts::value<std::string>())("mesh", "with a glTF rig: the mesh whose morph targets are the controllers",
                                     cxxopts::value<std::string>())(
      "weights", "weights.csv: frame,<controllers...>,residual_mm, one row per frame", cxxopts::value<std::string>())(
      "fps", "frames per second (row k plays at k / fps seconds)", cxxopts::value<double>()->default_value("30"))(
      "scale-to-metres",
      "metres per rig unit (glTF is in metres); default from the rig's units: cm 0.01, mm 0.001, m 1",
      cxxopts::value<double>())("out", "the file to write: .glb or .gltf", cxxopts::value<std::string>());
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  if (args.count("rig") == args.count("bundle"))
    throw Error("--rig, --bundle", "give the avatar's rig with one of them (see --help)");
  if (!args.count("weights")) throw Error("--weights", "give the weights table, weights.csv (see --help)");
  if (!args.count("out")) throw Error("--out", "give the file to write, .glb or .gltf (see --help)");

  GltfAnimationOptions gltf;
  gltf.fps = args["fps"].as<double>();
  if (args.count("scale-to-metres")) gltf.scale_to_metres = args["scale-to-metres"].as<double>();
  try {
    gltf.validate();
  } catch (const Error& e) {
    // The option as the user typed it.
    const std::string flag = e.where() == "gltf_animation.fps" ? "--fps" : "--scale-to-metres";
    throw Error(flag, e.detail());
  }

  const std::string out = args["out"].as<std::string>();
  std::string extension = std::filesystem::path(out).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (extension != ".glb" && extension != ".gltf")
    throw Error("--out " + out, "expected a file name ending in .glb (binary glTF) or .gltf (JSON)");

  Rig rig;
  if (args.count("bundle")) {
    const std::string folder = args["bundle"].as<std::string>();
    if (args.count("mesh")) throw Error("--mesh", "only with a glTF --rig, not with --bundle");
    LoadedBundle bundle = load_bundle(folder);
    if (!bundle.rig)
      throw Error("--bundle " + folder,
                  "the bundle carries no rig (exported before format 3, or without its avatar's rig); give --rig");
    rig = std::move(*bundle.rig);
  } else {
    rig = load_rig(args["rig"].as<std::string>(), args.count("mesh") ? args["mesh"].as<std::string>() : "");
  }
  try {
    gltf.scale_to_metres = gltf_scale_to_metres(rig.units, gltf);
  } catch (const Error& e) {
    throw Error("--scale-to-metres", e.detail());
  }
  WeightsCsv csv = read_weights_csv(args["weights"].as<std::string>());
  std::vector<std::string> names;
  for (const Controller& c : rig.controllers) names.push_back(c.name);
  require_weights_controllers(csv, names);

  const GltfAnimationSummary s = write_gltf_animation(gltf_animation_input(rig, std::move(csv.weights)), gltf, out);
  std::cout << fmt::format(
      "{}: {} frames ({:.3g} s at {:g} fps) x {} controllers on {} vertices, {} triangles; "
      "{:g} m per rig unit; {:.1f} KiB\n",
      out, s.frames, s.duration, gltf.fps, s.controllers, s.vertices, s.triangles, s.scale_to_metres, s.bytes / 1024.0);
  return 0;
}

}  // namespace retarget::cli
