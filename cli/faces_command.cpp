// `retarget faces DATASET --out DIR [--split test] [--subjects a,b] [--expressions x,y] [--force]`:
// the human meshes of a dataset's held-out people as files (data/test_faces.h).
#include <fmt/format.h>

#include <cxxopts.hpp>
#include <iostream>

#include "cli/commands.h"
#include "core/error.h"
#include "data/test_faces.h"

namespace retarget::cli {

int faces_command(int argc, char** argv) {
  cxxopts::Options options("retarget faces",
                           "Write the human meshes of a dataset's held-out (or training) people as OBJ files,\n"
                           "with faces.yaml naming each one's subject, expression and recipe weights: the\n"
                           "inputs of retarget-infer and `retarget eval retarget`.");
  TestFacesOptions faces;
  options.add_options()("dataset", "the human dataset folder", cxxopts::value<std::string>())(
      "out", "the folder to write", cxxopts::value<std::string>())(
      "split", "whose subjects: test, train or all", cxxopts::value<std::string>()->default_value("test"))(
      "subjects", "only these subjects (comma-separated names)", cxxopts::value<std::vector<std::string>>())(
      "expressions", "only these expressions (comma-separated names)", cxxopts::value<std::vector<std::string>>())(
      "force", "replace the files of a folder that is not empty")("h,help", "show this help");
  options.parse_positional({"dataset"});
  options.positional_help("DATASET");
  const cxxopts::ParseResult args = options.parse(argc, argv);
  if (args.count("help")) {
    std::cout << options.help() << "\n";
    return 0;
  }
  if (!args.count("dataset")) throw Error("retarget faces", "expected a human dataset folder (see --help)");
  if (!args.count("out")) throw Error("retarget faces", "expected --out DIR");
  faces.split = args["split"].as<std::string>();
  if (args.count("subjects")) faces.subjects = args["subjects"].as<std::vector<std::string>>();
  if (args.count("expressions")) faces.expressions = args["expressions"].as<std::vector<std::string>>();
  faces.force = args.count("force") > 0;
  const TestFaces written = write_test_faces(args["dataset"].as<std::string>(), args["out"].as<std::string>(), faces);
  std::cout << fmt::format("{} faces written into {} (faces.yaml lists them)\n", written.faces.size(), written.folder);
  return 0;
}

}  // namespace retarget::cli
