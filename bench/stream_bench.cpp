// retarget-infer --stream's latency, end to end: one ARKit row written into the stream's input
// pipe -> the face model's face -> DR features -> bundle.pt -> reconstruction -> the rig's
// weights -> the JSON line read back from its output pipe, one row at a time (nothing queued), on
// a random-weight bundle (bench/infer_benchmark.h) with a rig: an 11,090-vertex human (closed UV
// sphere, 100 x 112) into a 1,986-vertex avatar (UV sphere, 32 x 64) with 52 controllers; a face model of 52
// expressions (the human's smooth deformations) driven by 52 CSV columns, as Live Link Face writes them.
//
//   BM_StreamLatency: real time per iteration = one row in, its line out. line_latency_ms: the
//                     line's own latency_ms (row arrival to the line written); p99_ms: the
//                     stream summary's. Arguments: {encoder, threads}: encoder 0 = the paper's VAE
//                     sizes, 1 = the quick profile's; threads as retarget-infer --threads (0: every core).
//
// Run with scripts/bench.sh --benchmark_filter=BM_Stream (medians over repetitions).
#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "bench/infer_benchmark.h"
#include "geometry/face_model.h"
#include "geometry/primitive_meshes.h"
#include "infer/stream_run.h"
#include "infer/stream_socket.h"

namespace retarget {

// Named, not anonymous: unity batches share one anonymous namespace.
namespace stream_bench {

namespace fs = std::filesystem;
constexpr int kShapes = 52;  // ARKit's blendshapes; as many rig controllers

// 52 smooth bumps along the normal around spots spread over the sphere (a Fibonacci lattice), [0, 1] each.
BundleRig bump_rig(const Mesh& ball, double radius) {
  BundleRig part;
  part.rig.name = "bench-ball";
  part.rig.source = "bench-ball/rig.yaml";
  part.rig.neutral = ball;
  const Positions& n = ball.vertices;
  for (int k = 0; k < kShapes; ++k) {
    const double z = 1 - 2 * (k + 0.5) / kShapes, r = std::sqrt(1 - z * z), phi = k * 2.399963229728653;
    const Eigen::RowVector3d spot(r * std::cos(phi), r * std::sin(phi), z);
    Controller c;
    c.name = fmt::format("ctrl{:02d}", k);
    c.offset = Positions::Zero(n.rows(), 3);
    for (Eigen::Index i = 0; i < n.rows(); ++i) {
      const double d2 = (n.row(i) / radius - spot).squaredNorm();
      c.offset.row(i) = 0.05 * radius * std::exp(-d2 / 0.08) * n.row(i).normalized();
    }
    part.rig.controllers.push_back(std::move(c));
  }
  part.millimetres_per_unit = 10;
  return part;
}

// The prepared stream (bundle and face model on disk) of one encoder size (0: the paper's VAE
// sizes, 1: the quick profile's), made once per process.
const StreamOptions& prepared(int64_t encoder) {
  static std::map<int64_t, StreamOptions> made;
  if (const auto it = made.find(encoder); it != made.end()) return it->second;
  const fs::path folder = fs::temp_directory_path() / ("retarget_stream_bench_" + std::to_string(encoder));
  fs::remove_all(folder);
  fs::create_directories(folder);
  const Mesh human = uv_sphere(100, 112), avatar = uv_sphere(32, 64);
  RandomBundleOptions bundle;
  bundle.rig = bump_rig(avatar, 1.0);
  if (encoder == 1) bundle.channels = {9, 32, 16, 16, 16, 1};
  write_random_bundle(human, avatar, (folder / "bundle").string(), bundle);
  FaceModel model;
  model.name = "bench-face";
  model.source = "bench-face/face_model.yaml";
  model.neutral = human;
  const std::vector<Positions> frames = deformed_frames(human, kShapes);
  for (int k = 0; k < kShapes; ++k)
    model.expressions.push_back({fmt::format("shape{:02d}", k), frames[k] - human.vertices});
  write_face_model((folder / "face").string(), model);
  StreamOptions& options = made[encoder];
  options.bundle = (folder / "bundle").string();
  options.face_model = (folder / "face" / "face_model.yaml").string();
  return options;
}

// Row k: Timecode, BlendShapeCount, 52 weights in [0, 1].
std::string row(int k) {
  std::string text = fmt::format("12:00:{:02d}:{:02d}.000,{}", k / 60 % 60, k % 60, kShapes);
  for (int s = 0; s < kShapes; ++s) text += fmt::format(",{:.4f}", 0.5 + 0.5 * std::sin(0.37 * k + 1.1 * s));
  return text + "\n";
}

void BM_StreamLatency(benchmark::State& state) {
  StreamOptions options = prepared(state.range(0));
  options.threads = static_cast<int>(state.range(1));
  StreamRun stream(options);
  int rows_pipe[2], lines_pipe[2];
  if (::pipe(rows_pipe) != 0 || ::pipe(lines_pipe) != 0) {
    state.SkipWithError("no pipe");
    return;
  }
  auto in = std::make_unique<FdStream>(rows_pipe[0]);
  auto out = std::make_unique<FdStream>(lines_pipe[1]);
  StreamSummary summary;
  std::thread worker([&] { summary = stream.run(*in, *out); });
  auto rows = std::make_unique<FdStream>(rows_pipe[1]);
  FdStream lines(lines_pipe[0]);
  std::string header = "Timecode,BlendShapeCount";
  for (int s = 0; s < kShapes; ++s) header += fmt::format(",shape{:02d}", s);
  *rows << header << "\n" << std::flush;
  int k = 0;
  std::string line;
  double line_latency = 0;
  for (auto _ : state) {
    *rows << row(k++) << std::flush;
    if (!std::getline(lines, line)) {
      state.SkipWithError("the stream ended");
      break;
    }
    const size_t at = line.find("\"latency_ms\":");
    if (at != std::string::npos) line_latency += std::stod(line.substr(at + 13));
  }
  rows.reset();  // end of input: the stream ends
  worker.join();
  state.SetItemsProcessed(k);
  state.counters["line_latency_ms"] = benchmark::Counter(k > 0 ? line_latency / k : 0.0);
  state.counters["p99_ms"] = benchmark::Counter(summary.latency_percentile(99));
  state.SetLabel(fmt::format("{} encoder, 11,090 -> 1,986 vertices, 52 columns, 52 controllers, {} threads",
                             state.range(0) == 0 ? "paper" : "quick",
                             options.threads == 0 ? std::string("all") : std::to_string(options.threads)));
}
BENCHMARK(BM_StreamLatency)
    ->ArgNames({"encoder", "threads"})
    ->ArgsProduct({{0, 1}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace stream_bench
}  // namespace retarget
