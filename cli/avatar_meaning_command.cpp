// `retarget avatar meaning --rig RIG --face-model FACE_MODEL_YAML --out correspondence.yaml
// [--pictures DIR] [--no-names] [--picture-size N]`: proposes which human blendshapes each avatar
// controller stands for (correspond/controller_meaning.h), with a confidence per row and one
// picture per controller for a person to confirm.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cxxopts.hpp>
#include <filesystem>
#include <iostream>

#include "cli/command_options.h"
#include "cli/commands.h"
#include "core/error.h"
#include "correspond/controller_meaning.h"
#include "geometry/face_model.h"
#include "geometry/rig.h"

namespace retarget::cli {

namespace avatar_meaning_detail {

// A picture file name for a controller: its letters, digits, '-', '_' and '.', '_' for the rest.
std::string picture_name(const std::string& controller) {
  std::string name;
  for (char ch : controller) {
    const unsigned char c = static_cast<unsigned char>(ch);
    name.push_back(std::isalnum(c) || c == '-' || c == '_' || c == '.' ? ch : '_');
  }
  return name + ".png";
}

std::string row_text(const ControllerMeaning& meaning, const ControllerMeaningRow& row) {
  std::string entries;
  for (const auto& [shape, w] : meaning.table.at(row.controller))
    entries += (entries.empty() ? "" : ", ") + fmt::format("{}: {:.3g}", shape, w);
  std::string text =
      fmt::format("  {:<20} {{{}}}  confidence {:.2f} ({})", row.controller, entries, row.confidence, row.method);
  if (row.method != "name") {
    std::string evidence;
    for (size_t k = 0; k < std::min<size_t>(3, row.candidates.size()); ++k)
      evidence += fmt::format("{}{} {:.2f}", k ? ", " : "", row.candidates[k].shape, row.candidates[k].share);
    text += fmt::format("\n      coverage {:.2f}, human-like at most {:.2f}; largest shares: {}", row.coverage,
                        row.explained_by_all, evidence);
  }
  if (!row.note.empty()) text += "\n      note: " + row.note;
  return text;
}

}  // namespace avatar_meaning_detail

int avatar_meaning(int argc, char** argv) {
  cxxopts::Options options("retarget avatar meaning",
                           "Propose which human blendshapes each controller of an avatar rig stands for (the\n"
                           "rig's correspondence.yaml), by name where the controllers are named like the face\n"
                           "model's expressions, else by deformation transfer of every human shape onto the\n"
                           "avatar and a rig fit; with a confidence per row and a picture per controller to\n"
                           "confirm it by.");
  ControllerMeaningOptions meaning_options;
  options.add_options()("rig", "the avatar rig (rig.yaml, its folder, or .gltf/.glb)", cxxopts::value<std::string>())(
      "mesh", "glTF rigs: the mesh whose morph targets are the controllers", cxxopts::value<std::string>())(
      "face-model", "the human face model (face_model.yaml)", cxxopts::value<std::string>())(
      "out", "the correspondence.yaml to write", cxxopts::value<std::string>())(
      "pictures", "a folder for one PNG per controller (avatar beside the human)", cxxopts::value<std::string>())(
      "picture-size", "pixels per picture", cxxopts::value<int>()->default_value("256"))(
      "no-names", "match every controller by geometry, not by name")(
      "min-confidence", "rows explained less than this become {}",
      cxxopts::value<double>()->default_value(std::to_string(meaning_options.min_confidence)))(
      "landmark-weight",
      "how much what each face does at the shared landmarks (lids, brows, lips, mouth corners) counts against the "
      "transferred vertices (0: vertices only)",
      cxxopts::value<double>()->default_value(std::to_string(meaning_options.landmark_weight)));
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  if (!args.count("rig")) throw Error("retarget avatar meaning", "expected --rig RIG (see --help)");
  if (!args.count("face-model")) throw Error("retarget avatar meaning", "expected --face-model FACE_MODEL_YAML");
  if (!args.count("out")) throw Error("retarget avatar meaning", "expected --out correspondence.yaml");
  meaning_options.match_names = !args.count("no-names");
  meaning_options.min_confidence = args["min-confidence"].as<double>();
  meaning_options.landmark_weight = args["landmark-weight"].as<double>();
  MeaningPictureOptions picture_options;
  picture_options.size = args["picture-size"].as<int>();
  meaning_options.validate();
  if (args.count("pictures")) picture_options.validate();

  const Rig rig = load_rig(args["rig"].as<std::string>(), args.count("mesh") ? args["mesh"].as<std::string>() : "");
  const FaceModel face = load_face_model(args["face-model"].as<std::string>());
  const ControllerMeaning meaning = propose_controller_meaning(rig, face, meaning_options);
  const std::string out = args["out"].as<std::string>();
  write_controller_meaning(out, rig, face, meaning);

  std::cout << fmt::format("{}: {} controllers, {} human shapes ({:.1f} s)", rig.name, rig.controller_count(),
                           face.expressions.size(), meaning.seconds);
  if (meaning.transferred)
    std::cout << fmt::format("; deformation transfer over {} shared landmarks, fit distance {:.3g} {}",
                             meaning.landmarks.size(), meaning.transfer.mean_distance, rig.units);
  std::cout << "\n";
  for (const ControllerMeaningRow& row : meaning.rows)
    std::cout << avatar_meaning_detail::row_text(meaning, row) << "\n";
  std::cout << "written: " << out << "\n";
  if (args.count("pictures")) {
    const std::filesystem::path folder(args["pictures"].as<std::string>());
    for (const ControllerMeaningRow& row : meaning.rows)
      write_png((folder / avatar_meaning_detail::picture_name(row.controller)).string(),
                controller_meaning_picture(rig, face, meaning, row.controller, picture_options));
    std::cout << fmt::format("pictures: {} in {}\n", meaning.rows.size(), folder.string());
  }
  std::cout << "Check every row against its picture before using the table; edit the file where it is wrong.\n";
  return 0;
}

}  // namespace retarget::cli
