// `retarget faces DATASET --out DIR [--split test] [--subjects a,b] [--expressions x,y]
//   [--blends N --blend-seed S ...] [--no-references] [--force]`:
// the human meshes of a dataset's held-out people as files (data/test_faces.h), the reference
// expressions and, with --blends, random blends nobody annotated.
#include <fmt/format.h>

#include <cxxopts.hpp>
#include <iostream>

#include "cli/command_options.h"
#include "cli/commands.h"
#include "core/error.h"
#include "data/test_faces.h"

namespace retarget::cli {

int faces_command(int argc, char** argv) {
  cxxopts::Options options("retarget faces",
                           "Write the human meshes of a dataset's held-out (or training) people as OBJ files,\n"
                           "with faces.yaml naming each one's subject, expression and recipe weights: the\n"
                           "inputs of retarget-infer and `retarget eval retarget`. With --blends N, also N random\n"
                           "blends of the face model's shapes per person (unseen expressions, set \"blends\").");
  TestFacesOptions faces;
  options.add_options()("dataset", "the human dataset folder", cxxopts::value<std::string>())(
      "out", "the folder to write", cxxopts::value<std::string>())(
      "split", "whose subjects: test, train or all", cxxopts::value<std::string>()->default_value("test"))(
      "subjects", "only these subjects (comma-separated names)", cxxopts::value<std::vector<std::string>>())(
      "expressions", "only these expressions (comma-separated names)", cxxopts::value<std::vector<std::string>>())(
      "blends", "random blends of the face model's shapes per person (face-model datasets)",
      cxxopts::value<int>()->default_value("0"))("blend-seed", "seed of the blends",
                                                 cxxopts::value<uint64_t>()->default_value("1"))(
      "blend-min-shapes", "fewest shapes in a blend", cxxopts::value<int>()->default_value("1"))(
      "blend-max-shapes", "most shapes in a blend", cxxopts::value<int>()->default_value("4"))(
      "blend-min-weight", "smallest weight of a blended shape", cxxopts::value<double>()->default_value("0.3"))(
      "blend-max-weight", "largest weight of a blended shape", cxxopts::value<double>()->default_value("1"))(
      "no-references", "write only the blends (and each person's neutral face, which DT needs)")(
      "force", "replace the files of a folder that is not empty");
  options.parse_positional({"dataset"});
  options.positional_help("DATASET");
  const std::optional<cxxopts::ParseResult> parsed = parse_options(options, argc, argv);
  if (!parsed) return 0;
  const cxxopts::ParseResult& args = *parsed;
  if (!args.count("dataset")) throw Error("retarget faces", "expected a human dataset folder (see --help)");
  if (!args.count("out")) throw Error("retarget faces", "expected --out DIR");
  faces.split = args["split"].as<std::string>();
  if (args.count("subjects")) faces.subjects = args["subjects"].as<std::vector<std::string>>();
  if (args.count("expressions")) faces.expressions = args["expressions"].as<std::vector<std::string>>();
  faces.force = args.count("force") > 0;
  faces.blends.count = args["blends"].as<int>();
  faces.blends.seed = args["blend-seed"].as<uint64_t>();
  faces.blends.min_shapes = args["blend-min-shapes"].as<int>();
  faces.blends.max_shapes = args["blend-max-shapes"].as<int>();
  faces.blends.min_weight = args["blend-min-weight"].as<double>();
  faces.blends.max_weight = args["blend-max-weight"].as<double>();
  faces.references = args.count("no-references") == 0;
  const TestFaces written = write_test_faces(args["dataset"].as<std::string>(), args["out"].as<std::string>(), faces);
  std::cout << fmt::format("{} faces written into {} (faces.yaml lists them)\n", written.faces.size(), written.folder);
  return 0;
}

}  // namespace retarget::cli
