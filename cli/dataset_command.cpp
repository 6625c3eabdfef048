// retarget dataset: a rig, a face model or a face folder -> a dataset folder (data/dataset.h).
#include <fmt/format.h>

#include <cxxopts.hpp>
#include <filesystem>
#include <iostream>

#include "cli/command_options.h"
#include "cli/commands.h"
#include "cli/mesh_size_options.h"
#include "core/error.h"
#include "core/progress.h"
#include "data/dataset.h"
#include "data/dataset_preview.h"
#include "geometry/expression_blends.h"
#include "geometry/face_model.h"

namespace retarget::cli {

namespace fs = std::filesystem;

namespace {

std::string megabytes(int64_t bytes) {
  return bytes >= 1000000 ? fmt::format("{:.1f} MB", bytes / 1e6) : fmt::format("{:.1f} kB", bytes / 1e3);
}

void print_summary(const DatasetSummary& s) {
  std::cout << fmt::format("{} dataset {}: {} samples ({} train, {} test), {} vertices", to_string(s.kind), s.folder,
                           s.samples, s.train, s.test, s.vertices);
  if (s.kind == DatasetKind::avatar) std::cout << fmt::format(", {} controllers\n", s.controllers);
  if (!s.gltf_meshes.empty())
    std::cout << fmt::format("  glTF meshes (recorded; later steps reload these): {}\n",
                             fmt::join(s.gltf_meshes, ", "));
  else
    std::cout << fmt::format(", {} subjects x {} expressions\n", s.subjects, s.expressions);
  std::cout << fmt::format("  built in {} (meshes and DR features {})\n", format_duration(s.seconds),
                           format_duration(s.features_seconds));
  std::cout << fmt::format("  normaliser: training {}to [-0.9, 0.9], {} of {} dimensions widened to a range of 1e-5",
                           s.kind == DatasetKind::human ? "features and targets " : "features ", s.widened,
                           static_cast<int64_t>(s.vertices) * 9);
  if (s.kind == DatasetKind::human)
    std::cout << fmt::format(" (targets span [{:.3f}, {:.3f}])", s.targets_min, s.targets_max);
  if (s.test > 0)
    std::cout << fmt::format("\n  test features normalised: [{:.3f}, {:.3f}], {:.3g}% of values outside [-1, 1]",
                             s.test_min, s.test_max, 100 * s.test_outside);
  std::string files;
  for (const auto& [file, bytes] : s.file_bytes)
    files += fmt::format("{}{} {}", files.empty() ? "" : ", ", file, megabytes(bytes));
  std::cout << "\n  files: " << files << "\n";
}

}  // namespace

int dataset_command(int argc, char** argv) {
  cxxopts::Options options("retarget dataset",
                           "Build a dataset of DR features (data/dataset.h) from one of:\n"
                           "  --rig PATH                          an avatar rig (folder with rig.yaml, or .gltf/.glb)\n"
                           "  --face-model YAML --recipes YAML    a linear face model and expression recipes\n"
                           "  --face-folder DIR                   captured meshes DIR/<subject>/<expression>.obj");
  AvatarDatasetOptions avatar;
  HumanDatasetOptions human;
  options.add_options()("out", "the dataset folder to write", cxxopts::value<std::string>())(
      "force", "replace the dataset files in a folder that is not empty")(
      "seed", "random seed (samples or identities, and the split)", cxxopts::value<uint64_t>()->default_value("1"))(
      "weighting", "DR edge weights: cotangent or uniform", cxxopts::value<std::string>()->default_value("cotangent"))(
      "threads", "threads for the DR features (0: all cores)", cxxopts::value<int>()->default_value("0"))(
      "no-preview", "do not write preview.png (a few samples rebuilt from their features)");
  options.add_options("avatar")("rig", "avatar rig: a folder with rig.yaml, or a .gltf/.glb file",
                                cxxopts::value<std::string>())(
      "mesh",
      "glTF only: the mesh with the controllers (default: the one with the most morph targets); eye, teeth and "
      "tongue meshes found by name are added as parts (a rig.yaml with `gltf:` and `meshes:` chooses them all)",
      cxxopts::value<std::string>()->default_value(""))(
      "allow-no-eyes",
      "build from a rig without eyes (errors in mesh units; `retarget eval retarget` will refuse the avatar)")(
      "samples", "random rig expressions", cxxopts::value<int>()->default_value(std::to_string(avatar.samples)))(
      "min-active", "fewest controllers active per sample",
      cxxopts::value<int>()->default_value(std::to_string(avatar.min_active)))(
      "max-active", "most controllers active per sample",
      cxxopts::value<int>()->default_value(std::to_string(avatar.max_active)))(
      "test-fraction", "share of the samples held out", cxxopts::value<double>()->default_value("0.1"));
  options.add_options("human")("face-model", "a linear face model: face_model.yaml (or its folder)",
                               cxxopts::value<std::string>())(
      "recipes", "expression recipes YAML (e.g. configs/expressions/facewarehouse47.yaml)",
      cxxopts::value<std::string>())("people",
                                     "people drawn from the face model (0: enough training people to span its "
                                     "identity modes, at least 24)",
                                     cxxopts::value<int>()->default_value(std::to_string(human.people)))(
      "test-people", "subjects held out (default: 20%)", cxxopts::value<int>())(
      "face-folder", "a folder of <subject>/<expression>.obj meshes", cxxopts::value<std::string>())(
      "test-subjects", "face folder: the held-out subjects by name, comma-separated",
      cxxopts::value<std::vector<std::string>>())("neutral", "face folder: the neutral expression's name",
                                                  cxxopts::value<std::string>()->default_value("neutral"))(
      "rest", "face folder: the rest mesh (default: the mean of the training subjects' neutrals)",
      cxxopts::value<std::string>())(
      "blends",
      "face model: also N random blends of its shapes as expressions (train_blend000...), e.g. to annotate beside "
      "the recipes; the recipes with them are written to OUT/recipes.yaml",
      cxxopts::value<int>()->default_value("0"))("blend-seed",
                                                 "seed of those blends (keep it apart from the test "
                                                 "faces')",
                                                 cxxopts::value<uint64_t>()->default_value("1001"));
  add_mesh_size_options(options);
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv, {"", "avatar", "human"});
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  const int sources = static_cast<int>(args.count("rig") + args.count("face-model") + args.count("face-folder"));
  if (sources != 1) throw Error("give exactly one of --rig, --face-model, --face-folder (see --help)");
  if (!args.count("out")) throw Error("missing --out DIR (see --help)");
  const std::string out = args["out"].as<std::string>();

  DrOptions dr;
  dr.weighting = parse_edge_weighting(args["weighting"].as<std::string>(), "--weighting");
  dr.threads = args["threads"].as<int>();
  const bool force = args.count("force") > 0;
  const uint64_t seed = args["seed"].as<uint64_t>();
  const MeshSizeLimits size = mesh_size_limits(args);

  DatasetSummary summary;
  if (args.count("rig")) {
    avatar.samples = args["samples"].as<int>();
    avatar.min_active = args["min-active"].as<int>();
    avatar.max_active = args["max-active"].as<int>();
    avatar.test_fraction = args["test-fraction"].as<double>();
    avatar.mesh_name = args["mesh"].as<std::string>();
    avatar.require_eyes = args.count("allow-no-eyes") == 0;
    avatar.seed = seed;
    avatar.dr = dr;
    avatar.force = force;
    avatar.size = size;
    summary = build_avatar_dataset(args["rig"].as<std::string>(), out, avatar);
  } else {
    human.people = args["people"].as<int>();
    if (args.count("test-people")) human.test_people = args["test-people"].as<int>();
    if (args.count("test-subjects")) human.test_subjects = args["test-subjects"].as<std::vector<std::string>>();
    human.neutral = args["neutral"].as<std::string>();
    if (args.count("rest")) human.rest_mesh = args["rest"].as<std::string>();
    human.seed = seed;
    human.dr = dr;
    human.force = force;
    human.size = size;
    if (args.count("face-model")) {
      if (!args.count("recipes"))
        throw Error("--face-model needs --recipes (e.g. configs/expressions/facewarehouse47.yaml)");
      const std::string recipes_path = args["recipes"].as<std::string>();
      std::vector<ExpressionRecipe> recipes = load_expression_recipes(recipes_path);
      const FaceModel model = load_face_model(args["face-model"].as<std::string>());
      BlendOptions blends;
      blends.count = args["blends"].as<int>();
      blends.seed = args["blend-seed"].as<uint64_t>();
      blends.prefix = "train_blend";
      blends.validate("--blends");
      if (blends.count > 0) {
        std::vector<std::string> shapes;
        for (const auto& e : model.expressions) shapes.push_back(e.name);
        const std::vector<ExpressionRecipe> extra = random_blends(shapes, blends, recipes);
        recipes.insert(recipes.end(), extra.begin(), extra.end());
        human.own_recipes = true;  // written into the dataset, before its manifest
      }
      summary = build_human_dataset(model, recipes, recipes_path, out, human);
    } else {
      summary = build_face_folder_dataset(args["face-folder"].as<std::string>(), out, human);
    }
  }
  print_summary(summary);
  if (!args.count("no-preview")) {
    const std::string preview = (fs::path(out) / "preview.png").string();
    write_png(preview, dataset_preview(load_dataset(out)));
    std::cout << "  preview: " << preview << "\n";
  }
  return 0;
}

}  // namespace retarget::cli
