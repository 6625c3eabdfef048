// `retarget gltf-animation --rig RIG --weights weights.csv --out anim.glb [--fps 30]`: a
// controller-weight sequence (retarget-infer --weights) as a glTF 2.0 morph-target animation on
// the rig's neutral mesh, for engines (infer/gltf_animation.h).
#include <fmt/format.h>

#include <cctype>
#include <cxxopts.hpp>
#include <filesystem>
#include <iostream>

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
      "must be the rig's controllers, in its order.");
  options.add_options()("rig", "the avatar rig: a folder with rig.yaml, or a .gltf/.glb file",
                        cxxopts::value<std::string>())(
      "mesh", "with a glTF rig: the mesh whose morph targets are the controllers", cxxopts::value<std::string>())(
      "weights", "weights.csv: frame,<controllers...>,residual_mm, one row per frame", cxxopts::value<std::string>())(
      "fps", "frames per second (row k plays at k / fps seconds)", cxxopts::value<double>()->default_value("30"))(
      "scale-to-metres",
      "metres per rig unit (glTF is in metres); default from the rig's units: cm 0.01, mm 0.001, m 1",
      cxxopts::value<double>())("out", "the file to write: .glb or .gltf", cxxopts::value<std::string>())(
      "h,help", "show this help");
  const cxxopts::ParseResult args = options.parse(argc, argv);
  if (args.count("help")) {
    std::cout << options.help() << "\n";
    return 0;
  }
  for (const char* required : {"rig", "weights", "out"})
    if (!args.count(required)) throw Error("retarget gltf-animation", fmt::format("give --{} (see --help)", required));

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

  const Rig rig = load_rig(args["rig"].as<std::string>(), args.count("mesh") ? args["mesh"].as<std::string>() : "");
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
