// retarget-infer benchmarks with a random-weight bundle (bench/infer_benchmark.h): an 11,090-vertex
// human (closed UV sphere, 100 x 112) into a 1,986-vertex avatar (UV sphere, 32 x 64), with the
// human and avatar VAEs at the paper's sizes (graph convs 9-128-64-64-64-1) or the quick
// profile's (9-32-16-16-16-1); hidden 300, latent 25 either way. Frames are smooth deformations
// of the human rest written as OBJ files once per architecture (in the system's temp folder).
//
//   BM_InferBatch:   one run_inference over all frames (files in, files out, batch 8, all cores),
//                    as `retarget-infer --bundle B IN --out OUT` runs them. frames_per_s: the whole
//                    run (setup included); <stage>_ms: milliseconds per frame of each stage.
//   BM_InferLatency: one frame at a time through the Retargeter (read the OBJ, DR features,
//                    bundle.pt, reconstruction with alignment, write the OBJ): the latency a
//                    streaming caller sees. <stage>_ms per frame as above.
//
// Arguments: {encoder, threads, precision}: encoder 0 = paper sizes, 1 = quick profile; threads as
// retarget-infer --threads (0: every core); precision of the network's products as retarget-infer
// --precision: 0 float32, 1 bfloat16, 2 int8 (skipped, saying so, on a CPU without them). Run with
// scripts/bench.sh --benchmark_filter=BM_Infer (medians over repetitions).
#include <benchmark/benchmark.h>
#include <torch/torch.h>

#include <array>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "bench/infer_benchmark.h"
#include "core/timer.h"
#include "export/bundle_export.h"
#include "geometry/dr_pack_lanes.h"
#include "geometry/mesh_io.h"
#include "infer/infer_run.h"
#include "infer/memory_reuse.h"
#include "infer/retargeter.h"

namespace {

using namespace retarget;
namespace fs = std::filesystem;

constexpr int kFrames = 96;  // per BM_InferBatch iteration: 12 batches of 8
constexpr int kBatch = 8;

struct Encoder {
  const char* name;
  std::vector<int64_t> channels;
};

const std::array<Encoder, 2> kEncoders{{{"paper", {9, 128, 64, 64, 64, 1}}, {"quick", {9, 32, 16, 16, 16, 1}}}};

// The prepared run (bundle and frames on disk) of one architecture, made once per process.
const InferOptions& prepared(int64_t encoder) {
  static std::map<int64_t, InferOptions> runs;
  auto it = runs.find(encoder);
  if (it == runs.end()) {
    InferBenchmarkOptions options;
    options.folder =
        (fs::temp_directory_path() / ("retarget_infer_bench_" + std::string(kEncoders.at(encoder).name))).string();
    options.avatar_rings = 32;
    options.avatar_segments = 64;  // 1,986 vertices
    options.frames = kFrames;
    options.bundle.channels = kEncoders.at(encoder).channels;
    options.run.batch = kBatch;
    options.run.progress = nullptr;
    it = runs.emplace(encoder, prepare_inference_benchmark(options)).first;
  }
  return it->second;
}

// The precision argument (0 float32, 1 bfloat16, 2 int8).
NetworkPrecision precision_arg(int64_t value) {
  return value == 1 ? NetworkPrecision::bfloat16 : value == 2 ? NetworkPrecision::int8 : NetworkPrecision::float32;
}

// Skips the benchmark when this CPU lacks `precision` (the run would measure float32 instead).
bool skipped_for_precision(benchmark::State& state, NetworkPrecision precision) {
  if (network_precision_available(precision)) return false;
  state.SkipWithError((std::string("no ") + to_string(precision) + " products on this CPU").c_str());
  return true;
}

// kernel: what the graph convs' products called (network_products_kernel), or "scripted"; the
// native network's other loops are named too (network_loops_kernel).
void set_label(benchmark::State& state, int vertices_avatar, int batch, const std::string& kernel) {
  // torch::get_num_threads(): what run_inference set from the threads argument.
  const std::string loops = kernel == "scripted" ? "" : ", loops: " + network_loops_kernel();
  state.SetLabel(std::string(kEncoders.at(state.range(0)).name) + " encoder, 11,090 -> " +
                 std::to_string(vertices_avatar) + " vertices, batch " + std::to_string(batch) + ", " +
                 std::to_string(torch::get_num_threads()) + " threads, products: " + kernel + loops +
                 ", DR lanes: " + dr_lanes_name());
}

// Milliseconds per frame of a stage, averaged over every frame of every iteration.
benchmark::Counter per_frame_ms(double seconds, double frames) {
  return benchmark::Counter(frames > 0 ? 1000.0 * seconds / frames : 0.0);
}

void BM_InferBatch(benchmark::State& state) {
  InferOptions run = prepared(state.range(0));
  run.threads = static_cast<int>(state.range(1));
  run.precision = precision_arg(state.range(2));
  if (skipped_for_precision(state, run.precision)) return;
  InferTimings sum;
  double frames = 0;
  int avatar_vertices = 0;
  for (auto _ : state) {
    const InferSummary summary = run_inference(run);
    if (summary.done != kFrames) state.SkipWithError("not every frame was retargeted");
    const InferTimings& t = summary.seconds;
    sum.setup += t.setup;
    sum.read += t.read;
    sum.features += t.features;
    sum.network += t.network;
    sum.reconstruction += t.reconstruction;
    sum.write += t.write;
    sum.total += t.total;
    frames += summary.done;
    avatar_vertices = summary.avatar_vertices;
  }
  state.SetItemsProcessed(static_cast<int64_t>(frames));
  state.counters["frames_per_s"] = benchmark::Counter(sum.total > 0 ? frames / sum.total : 0.0);
  state.counters["setup_ms"] = per_frame_ms(sum.setup, frames);
  state.counters["read_ms"] = per_frame_ms(sum.read, frames);
  state.counters["features_ms"] = per_frame_ms(sum.features, frames);
  state.counters["network_ms"] = per_frame_ms(sum.network, frames);
  state.counters["reconstruction_ms"] = per_frame_ms(sum.reconstruction, frames);
  state.counters["write_ms"] = per_frame_ms(sum.write, frames);
  set_label(state, avatar_vertices, kBatch, network_products_kernel(run.precision));
}
BENCHMARK(BM_InferBatch)
    ->ArgNames({"encoder", "threads", "precision"})
    ->ArgsProduct({{0, 1}, {0, 1}, {0}})
    ->ArgsProduct({{0}, {0, 1}, {1, 2}})
    ->Args({1, 0, 1})
    ->Args({1, 0, 2})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_InferLatency(benchmark::State& state) {
  const InferOptions& run = prepared(state.range(0));
  // As run_inference does: every core for LibTorch and the geometry, tensor memory reused.
  const int threads = infer_threads(static_cast<int>(state.range(1)));
  torch::set_num_threads(threads);
  reuse_tensor_memory();
  RetargeterOptions options;
  options.threads = threads;
  options.precision = precision_arg(state.range(2));
  if (skipped_for_precision(state, options.precision)) return;
  Retargeter retargeter(load_bundle(run.bundle), options);
  const std::string input = (fs::path(run.inputs.front()) / "frame_1.obj").string();
  const std::string output = (fs::path(run.out) / "latency.obj").string();
  fs::create_directories(run.out);
  std::array<double, 5> seconds{};  // read, features, network, reconstruction, write
  double frames = 0;
  for (auto _ : state) {
    Stopwatch clock;
    const Mesh human = read_mesh(input);
    seconds[0] += clock.restart();
    const torch::Tensor x = retargeter.features({&human.vertices});
    seconds[1] += clock.restart();
    const torch::Tensor y = retargeter.translate(x);
    seconds[2] += clock.restart();
    const std::vector<Positions> avatar = retargeter.reconstruct(y);
    seconds[3] += clock.restart();
    write_mesh(output, with_positions(retargeter.bundle().avatar_rest, avatar.front()));
    seconds[4] += clock.restart();
    frames += 1;
  }
  state.SetItemsProcessed(static_cast<int64_t>(frames));
  const char* names[] = {"read_ms", "features_ms", "network_ms", "reconstruction_ms", "write_ms"};
  for (size_t k = 0; k < seconds.size(); ++k) state.counters[names[k]] = per_frame_ms(seconds[k], frames);
  set_label(state, retargeter.avatar_vertices(), 1, network_products_kernel(retargeter.precision()));
}
BENCHMARK(BM_InferLatency)
    ->ArgNames({"encoder", "threads", "precision"})
    ->ArgsProduct({{0, 1}, {0, 1}, {0}})
    ->ArgsProduct({{0}, {0, 1}, {1, 2}})
    ->Args({1, 0, 1})
    ->Args({1, 0, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The network alone (Retargeter::translate) on a fixed batch of features: the bundle's scripted
// forward (native 0) against the native encoder (native 1 float32, 2 bfloat16, 3 int8;
// infer/retargeter_network.h), in one process. Args {encoder, native, batch, threads}; ms per
// frame in network_ms.
void BM_InferNetwork(benchmark::State& state) {
  const InferOptions& run = prepared(state.range(0));
  const int threads = infer_threads(static_cast<int>(state.range(3)));
  torch::set_num_threads(threads);
  reuse_tensor_memory();
  RetargeterOptions options;
  options.threads = threads;
  options.native_network = state.range(1) != 0;
  options.precision = precision_arg(std::max<int64_t>(0, state.range(1) - 1));
  if (skipped_for_precision(state, options.precision)) return;
  Retargeter retargeter(load_bundle(run.bundle), options);
  if (retargeter.native_network() != options.native_network) state.SkipWithError("no native network");
  const int batch = static_cast<int>(state.range(2));
  const Mesh human = read_mesh((fs::path(run.inputs.front()) / "frame_1.obj").string());
  const std::vector<const Positions*> frames(batch, &human.vertices);
  const torch::Tensor x = retargeter.features(frames);
  double frames_done = 0, seconds = 0;
  for (auto _ : state) {
    Stopwatch clock;
    const torch::Tensor y = retargeter.translate(x);
    benchmark::DoNotOptimize(y.data_ptr<float>());
    seconds += clock.restart();
    frames_done += batch;
  }
  state.SetItemsProcessed(static_cast<int64_t>(frames_done));
  state.counters["network_ms"] = per_frame_ms(seconds, frames_done);
  set_label(state, retargeter.avatar_vertices(), batch,
            retargeter.native_network() ? network_products_kernel(retargeter.precision()) : "scripted");
}
BENCHMARK(BM_InferNetwork)
    ->ArgNames({"encoder", "native", "batch", "threads"})
    ->ArgsProduct({{0, 1}, {0, 1, 2, 3}, {1, 8}, {1, 0}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
