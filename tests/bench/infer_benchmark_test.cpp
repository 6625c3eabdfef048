#include "bench/infer_benchmark.h"

// LibTorch before Catch: glog (through c10) defines CHECK, and the last definition wins.
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>

#include "geometry/mesh_io.h"
#include "tests/infer/infer_test_support.h"

namespace retarget {
namespace {

namespace fs = std::filesystem;

TEST_CASE("run_inference_benchmark runs the whole runtime on random models", "[infer_benchmark]") {
  InferBenchmarkOptions options;
  options.folder = test::scratch_dir("infer_benchmark_small").string();
  options.human_rings = 12;
  options.human_segments = 16;  // 178 vertices
  options.avatar_rings = 8;
  options.avatar_segments = 10;  // 72 vertices
  options.frames = 7;
  options.bundle = test::tiny_bundle_options();
  options.run.batch = 3;
  options.run.progress = nullptr;
  const InferSummary summary = run_inference_benchmark(options);
  CHECK(summary.inputs == 7);
  CHECK(summary.done == 7);
  CHECK(summary.failed() == 0);
  CHECK(summary.avatar_vertices == 72);
  CHECK(fs::path(summary.outputs.back()).filename() == "frame_7.obj");
  CHECK(read_mesh(summary.outputs.front()).vertex_count() == 72);
  CHECK(summary.seconds.network > 0);
  CHECK(summary.frames_per_second(summary.seconds.total) > 0);
}

// Timing at the sizes of the real use (not part of the suite: hidden tag). Run with
//   tests_infer "[.timing]" -s     and optionally RETARGET_INFER_FRAMES / _BATCH / _THREADS.
TEST_CASE("run_inference_benchmark: 11k-vertex human, 2.5k-vertex avatar, default VAE sizes", "[.timing]") {
  auto number = [](const char* name, int fallback) {
    const char* value = std::getenv(name);
    return value ? std::atoi(value) : fallback;
  };
  InferBenchmarkOptions options;
  options.folder = test::scratch_dir("infer_benchmark_timing").string();
  options.frames = number("RETARGET_INFER_FRAMES", 300);
  options.run.batch = number("RETARGET_INFER_BATCH", 8);
  options.run.threads = number("RETARGET_INFER_THREADS", 0);
  options.run.progress = nullptr;
  const InferSummary summary = run_inference_benchmark(options);
  std::cout << "batch " << options.run.batch << ": " << format_summary(summary);
  CHECK(summary.done == options.frames);
}

}  // namespace
}  // namespace retarget
