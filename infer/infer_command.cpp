// retarget-infer's command line: maps the options onto InferOptions, RigHeadRunOptions or the
// stream's options (infer/infer_command.h). The work is in infer/infer_run.h and beside it.
#include "infer/infer_command.h"

#include <cxxopts.hpp>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/option_errors.h"
#include "infer/arkit_faces.h"
#include "infer/infer_run.h"
#include "infer/rig_head_run.h"
#include "infer/stream_cli.h"

namespace {

// retarget-infer --rig-map: the rig head (infer/rig_head_run.h); the network's options do not apply.
int run_rig_head_command(const cxxopts::ParseResult& args) {
  for (const char* option :
       {"render", "animation", "weights-ridge", "weights-smoothness", "bf16", "precision", "identity", "batch"})
    if (args.count(option))
      throw retarget::Error(std::string("--") + option,
                            "not with --rig-map (the rig head writes the rig's own weights, without the network)");
  retarget::RigHeadRunOptions options;
  if (args.count("bundle")) options.bundle = args["bundle"].as<std::string>();
  options.rig_map = args["rig-map"].as<std::string>();
  if (args.count("face-model")) options.face_model = args["face-model"].as<std::string>();
  if (args.count("arkit")) options.arkit = args["arkit"].as<std::string>();
  if (args.count("inputs")) options.inputs = args["inputs"].as<std::vector<std::string>>();
  if (args.count("out")) options.out = args["out"].as<std::string>();
  options.format = args["format"].as<std::string>();
  if (args.count("gltf")) options.gltf = args["gltf"].as<std::string>();
  options.fps = args["fps"].as<double>();
  std::cout << retarget::format_rig_head_summary(retarget::run_rig_head(options));
  return 0;
}

// --precision NAME (or --bf16): what the network's products run in.
retarget::NetworkPrecision network_precision_option(const cxxopts::ParseResult& args) {
  if (args.count("bf16") && args.count("precision"))
    throw retarget::Error("--bf16", "give --precision or --bf16, not both");
  if (args.count("bf16")) return retarget::NetworkPrecision::bfloat16;
  if (!args.count("precision")) return retarget::NetworkPrecision::float32;
  const std::string text = args["precision"].as<std::string>();
  const std::optional<retarget::NetworkPrecision> precision = retarget::parse_network_precision(text);
  if (!precision) throw retarget::Error("--precision", "\"" + text + "\" is not float32, bfloat16 or int8");
  return *precision;
}

}  // namespace

namespace retarget {

int infer_command(int argc, char** argv) {
  using retarget::Error;
  cxxopts::Options cli(
      "retarget-infer",
      "Carries human expressions onto an avatar: each input mesh (the bundle's human topology) becomes\n"
      "OUT/<name>.obj on the avatar's mesh. Inputs are files, folders (their .obj/.ply/.off files) or\n"
      "glob patterns, each in natural order (frame_2 before frame_10). Or an ARKit take (--arkit take.csv\n"
      "or .jsonl, blendshape weights per frame from Live Link Face or MediaPipe) through the face model\n"
      "the bundle's human side was made from: OUT/frame_000000.obj, ... and OUT/frames.csv.\n"
      "Exit status: 0 all done, 1 some inputs failed (reported, the others written), 2 nothing ran\n"
      "(bad options or bundle), 3 the run stopped on an unexpected error (out of memory, a library's\n"
      "error; the message says which).");
  cli.add_options()("bundle", "bundle folder (manifest.yaml, bundle.pt, human_rest.obj, avatar_rest.obj)",
                    cxxopts::value<std::string>())("out", "output folder", cxxopts::value<std::string>())(
      "format", "output format: obj or ply", cxxopts::value<std::string>()->default_value("obj"))(
      "strict", "stop at the first input that fails")("batch", "frames per network forward",
                                                      cxxopts::value<int>()->default_value("8"))(
      "threads", "CPU threads, 0: all cores", cxxopts::value<int>()->default_value("0"))(
      "precision",
      "the network's graph-conv products: float32, bfloat16 (where the CPU has AVX512-BF16; codes within ~0.05% "
      "of float32's) or int8 (where it has AVX512-VNNI; codes within ~1%)",
      cxxopts::value<std::string>())("bf16", "the same as --precision bfloat16")(
      "render", "also write OUT/<name>.png: input | output")(
      "align-to-rest", "align each output rigidly to the avatar rest pose (the default)")(
      "no-align", "keep each output as reconstructed (parts keep their rest centroids)")(
      "no-anchors", "let the avatar's still vertices move too (they are held at rest by default)")(
      "no-part-motion",
      "keep the avatar's rigid parts (eyeballs, teeth) at their rest places instead of moving them "
      "where its rig puts them (bundles with a rig)")(
      "weights", "also write the avatar rig's controller weights per frame: OUT/weights.csv, OUT/weights.jsonl")(
      "weights-ridge", "pull of the weights towards the neutral, >= 0 (scale-free)",
      cxxopts::value<double>()->default_value("0.0001"))("weights-smoothness",
                                                         "pull towards the previous frame's weights, >= 0 (sequences)",
                                                         cxxopts::value<double>()->default_value("0"))(
      "weights-format", "csv, jsonl or both", cxxopts::value<std::string>()->default_value("both"))(
      "gltf", "with --weights: also the frames as a glTF animation of the avatar's morph targets (.glb or .gltf)",
      cxxopts::value<std::string>())(
      "animation",
      "also the input | output pictures of the frames as one animation: .mp4 (through the ffmpeg program), .gif "
      "or .png (APNG)",
      cxxopts::value<std::string>())("fps", "frames per second of the --gltf and --animation animations",
                                     cxxopts::value<double>()->default_value("30"))(
      "rig-map",
      "the rig head instead of the network: MAP.yaml (retarget rig-map fit) takes the face model's blendshape "
      "weights (the take's, or fitted to each input mesh with --face-model) to the bundle rig's controller "
      "weights; writes the rig's meshes and OUT/weights.csv (and --gltf); with --stream, each row's weights live",
      cxxopts::value<std::string>())("arkit",
                                     "an ARKit take in place of input meshes: Live Link Face CSV or JSON lines",
                                     cxxopts::value<std::string>())(
      "face-model", "with --arkit: the face model the take drives (face_model.yaml or its folder)",
      cxxopts::value<std::string>())(
      "identity",
      "with --arkit: the person's identity coefficients c1,c2,... (default: the mean face; "
      "--identity=-1,0.5 when the first is negative)",
      cxxopts::value<std::string>())("inputs", "mesh files, folders or glob patterns",
                                     cxxopts::value<std::vector<std::string>>())("version", "print the version")(
      "h,help", "show this help");
  retarget::add_stream_options(cli);
  cli.parse_positional({"inputs"});
  cli.positional_help("--bundle B INPUT... --out DIR  |  --bundle B --arkit TAKE --face-model M --out DIR");
  try {
    const cxxopts::ParseResult args = cli.parse(argc, argv);
    if (args.count("help")) {
      std::cout << cli.help() << "\n";
      return 0;
    }
    if (args.count("version")) {
      std::cout << RETARGET_VERSION << "\n";
      return 0;
    }
    if (args.count("stream")) return retarget::run_stream_command(args);
    if (args.count("rig-map")) return run_rig_head_command(args);
    if (args.count("align-to-rest") && args.count("no-align")) {
      throw Error("--no-align", "contradicts --align-to-rest; give one of them");
    }
    retarget::InferOptions options;
    if (args.count("bundle")) options.bundle = args["bundle"].as<std::string>();
    if (args.count("inputs")) options.inputs = args["inputs"].as<std::vector<std::string>>();
    if (args.count("arkit")) options.arkit = args["arkit"].as<std::string>();
    if (args.count("face-model")) options.face_model = args["face-model"].as<std::string>();
    if (args.count("identity")) {
      const Eigen::VectorXd identity = retarget::parse_identity(args["identity"].as<std::string>());
      options.identity.assign(identity.data(), identity.data() + identity.size());
    }
    if (args.count("out")) options.out = args["out"].as<std::string>();
    options.format = args["format"].as<std::string>();
    options.strict = args.count("strict") > 0;
    options.batch = args["batch"].as<int>();
    options.threads = args["threads"].as<int>();
    options.render = args.count("render") > 0;
    options.align_to_rest = args.count("no-align") == 0;
    options.anchors = args.count("no-anchors") == 0;
    options.part_motion = args.count("no-part-motion") == 0;
    options.precision = network_precision_option(args);
    options.weights = args.count("weights") > 0;
    options.weights_ridge = args["weights-ridge"].as<double>();
    options.weights_smoothness = args["weights-smoothness"].as<double>();
    options.weights_format = args["weights-format"].as<std::string>();
    if (args.count("gltf")) options.gltf = args["gltf"].as<std::string>();
    if (args.count("animation")) options.animation = args["animation"].as<std::string>();
    options.fps = args["fps"].as<double>();

    const retarget::InferSummary summary = retarget::run_inference(options);
    std::cout << retarget::format_summary(summary);
    return summary.failed() == 0 ? 0 : 1;
  } catch (const Error& e) {
    std::cerr << "retarget-infer: " << e.what() << "\n";
  } catch (const cxxopts::exceptions::exception& e) {
    std::cerr << "retarget-infer: " << retarget::explain_option_error(e.what(), argc, argv) << " (see --help)\n";
  } catch (...) {
    std::cerr << "retarget-infer: " << retarget::describe_current_exception() << "\n";
    return 3;
  }
  return 2;
}

}  // namespace retarget
