// retarget-infer --stream's command line: its options and the mapping onto StreamOptions
// (infer/stream_run.h). Header-only, for infer/main.cpp alone (cxxopts is the executable's).
#pragma once

#include <fmt/format.h>

#include <cxxopts.hpp>
#include <iostream>
#include <string>
#include <vector>

#include "core/error.h"
#include "infer/arkit_faces.h"
#include "infer/stream_run.h"

namespace retarget {

inline void add_stream_options(cxxopts::Options& cli) {
  cli.add_options("stream")(
      "stream",
      "live: ARKit rows (CSV with its header line, or JSON lines) from stdin or --listen, one JSON line of "
      "the rig's weights per frame to stdout (or the socket) as soon as it is ready; a summary on stderr")(
      "listen", "with --stream: accept one client on 127.0.0.1:PORT instead of stdin/stdout", cxxopts::value<int>())(
      "arkit-columns", "with --stream: the CSV header (\"Timecode,EyeBlinkLeft,JawOpen,...\"); every line is a frame",
      cxxopts::value<std::string>())("drop", "with --stream: take the newest waiting row, drop older waiting rows")(
      "max-latency-ms", "with --stream: drop waiting rows older than this when a newer one waits",
      cxxopts::value<double>())("stream-meshes", "with --stream: also write DIR/frame_<n>.obj, the avatar mesh",
                                cxxopts::value<std::string>());
}

// Runs the stream of the command line (the shared options: --bundle, --face-model, --identity,
// --threads, --no-align, --no-anchors, --no-part-motion, --weights-ridge, --weights-smoothness); the summary goes to
// stderr. Returns the exit status. Throws retarget::Error for options that do not go with --stream.
inline int run_stream_command(const cxxopts::ParseResult& args) {
  for (const char* other : {"inputs", "arkit", "out", "gltf", "render", "weights"})
    if (args.count(other))
      throw Error(std::string("--") + other,
                  "not with --stream (the stream reads ARKit rows from stdin or --listen and writes weights lines)");
  StreamOptions options;
  if (args.count("bundle")) options.bundle = args["bundle"].as<std::string>();
  if (args.count("face-model")) options.face_model = args["face-model"].as<std::string>();
  if (args.count("identity")) {
    const Eigen::VectorXd identity = parse_identity(args["identity"].as<std::string>());
    options.identity.assign(identity.data(), identity.data() + identity.size());
  }
  if (args.count("listen")) {
    options.listen = args["listen"].as<int>();
    if (options.listen <= 0)
      throw Error("--listen", "expected a TCP port from 1 to 65535, got " + std::to_string(options.listen));
  }
  if (args.count("arkit-columns")) options.arkit_columns = args["arkit-columns"].as<std::string>();
  options.drop = args.count("drop") > 0;
  if (args.count("max-latency-ms")) {
    options.max_latency_ms = args["max-latency-ms"].as<double>();
    if (!(options.max_latency_ms > 0))
      throw Error("--max-latency-ms", fmt::format("expected milliseconds > 0, got {}", options.max_latency_ms));
  }
  if (args.count("stream-meshes")) options.meshes = args["stream-meshes"].as<std::string>();
  if (args.count("rig-map")) options.rig_map = args["rig-map"].as<std::string>();
  options.weights_ridge = args["weights-ridge"].as<double>();
  options.weights_smoothness = args["weights-smoothness"].as<double>();
  options.threads = args["threads"].as<int>();
  options.align_to_rest = args.count("no-align") == 0;
  options.anchors = args.count("no-anchors") == 0;
  options.part_motion = args.count("no-part-motion") == 0;
  const StreamSummary summary = run_stream(options);
  std::cerr << format_stream_summary(summary);
  return 0;
}

}  // namespace retarget
