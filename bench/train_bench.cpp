// Mesh VAE benchmarks with the default architecture (models/mesh_vae.h): one Adam training step
// of the avatar VAE (~2k vertices) and of the human expression VAE (~11k vertices), and encoder
// inference. Uses the real meshes (Weboji rabbit, 2,099 vertices; ICT face, 11,248 vertices) when
// RETARGET_SHARED_DATA (default: <source>/../shared/data) has them, otherwise closed UV spheres
// of 1,952 and 11,090 vertices. Inputs are random features in [-0.9, 0.9]; only the graph's
// size and sparsity matter for speed.
//
// Arguments: {batch, threads}; threads is torch::set_num_threads for the benchmark (restored
// afterwards, as it also sets the OpenMP thread count the other benchmarks use).
#include <benchmark/benchmark.h>
#include <torch/torch.h>

#include <array>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "bench/shared_data.h"
#include "geometry/mesh_io.h"
#include "geometry/mesh_topology.h"
#include "geometry/primitive_meshes.h"
#include "models/graph_operator.h"
#include "models/losses.h"
#include "models/mesh_vae.h"

namespace {

using namespace retarget;
namespace fs = std::filesystem;

constexpr double kKlWeight = 1e-5;  // the human VAE's (method notes); the value does not change the cost
constexpr double kLearningRate = 1e-4;

struct Graph {
  torch::Tensor laplacian;  // [V, V] sparse COO, graph_operator()
  int64_t vertices = 0;
  std::string name;
};

Graph make_graph(const Mesh& mesh, std::string name) {
  const std::vector<std::array<int, 2>> edges = edge_topology(mesh.triangles).edges;
  std::vector<int64_t> flat;
  flat.reserve(edges.size() * 2);
  for (const auto& e : edges) flat.insert(flat.end(), {e[0], e[1]});
  Graph g;
  g.vertices = mesh.vertex_count();
  g.laplacian = graph_operator(torch::tensor(flat, torch::kInt64).view({-1, 2}), g.vertices);
  g.name = std::move(name);
  return g;
}

// The real mesh at `relative` under the shared data folder, else a UV sphere.
Graph load_graph(const fs::path& relative, const std::string& real_name, int rings, int segments) {
  const fs::path path = retarget::bench::shared_data() / relative;
  if (fs::exists(path)) return make_graph(read_mesh(path.string()), real_name);
  return make_graph(uv_sphere(rings, segments), "synthetic sphere");
}

const Graph& avatar_graph() {
  static const Graph g = load_graph(fs::path("weboji") / "lapin" / "neutral.obj", "Weboji rabbit", 40, 50);
  return g;
}

const Graph& human_graph() {
  static const Graph g = load_graph(fs::path("ict-face") / "neutral.obj", "ICT face", 100, 112);
  return g;
}

// Sets torch's intra-op (and so OpenMP and OpenBLAS) thread count for one benchmark.
class ThreadCount {
 public:
  explicit ThreadCount(int64_t threads) : previous_(torch::get_num_threads()) {
    torch::set_num_threads(static_cast<int>(threads));
  }
  ~ThreadCount() { torch::set_num_threads(previous_); }
  ThreadCount(const ThreadCount&) = delete;
  ThreadCount& operator=(const ThreadCount&) = delete;

 private:
  int previous_;
};

void set_label(benchmark::State& state, const Graph& graph) {
  state.SetLabel(graph.name + ", " + std::to_string(graph.vertices) + " vertices, batch " +
                 std::to_string(state.range(0)) + ", " + std::to_string(state.range(1)) + " threads");
}

// Random DR-like features in [-0.9, 0.9]: [B, V, 9].
torch::Tensor random_features(int64_t batch, int64_t vertices) { return torch::rand({batch, vertices, 9}) * 1.8 - 0.9; }

// One step: forward with sampling, L1 + kl_weight * KL, backward, Adam. Items are samples.
void train_step(benchmark::State& state, const Graph& graph) {
  const int64_t batch = state.range(0);
  const ThreadCount threads(state.range(1));
  torch::manual_seed(0);
  MeshVae vae(graph.laplacian, MeshVaeOptions(graph.vertices));
  torch::optim::Adam adam(vae->parameters(), torch::optim::AdamOptions(kLearningRate));
  const torch::Tensor x = random_features(batch, graph.vertices);
  for (auto _ : state) {
    adam.zero_grad();
    const VaeOutput out = vae->forward(x, /*sample=*/true);
    const VaeLoss loss = vae_loss(out.reconstruction, x, out.mean, out.logvar, kKlWeight);
    loss.total.backward();
    adam.step();
  }
  state.SetItemsProcessed(state.iterations() * batch);
  set_label(state, graph);
}

void BM_AvatarVaeTrainStep(benchmark::State& state) { train_step(state, avatar_graph()); }
BENCHMARK(BM_AvatarVaeTrainStep)
    ->ArgNames({"batch", "threads"})
    ->Args({30, 1})
    ->Args({30, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_HumanVaeTrainStep(benchmark::State& state) { train_step(state, human_graph()); }
BENCHMARK(BM_HumanVaeTrainStep)
    ->ArgNames({"batch", "threads"})
    ->ArgsProduct({{1, 30}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The encoder's mean only, as the exported human encoder runs it. per_sample: seconds per sample.
void BM_EncoderInference(benchmark::State& state) {
  const Graph& graph = human_graph();
  const int64_t batch = state.range(0);
  const ThreadCount threads(state.range(1));
  torch::manual_seed(0);
  MeshVae vae(graph.laplacian, MeshVaeOptions(graph.vertices));
  vae->eval();
  const torch::Tensor x = random_features(batch, graph.vertices);
  torch::NoGradGuard no_grad;
  c10::InferenceMode inference;
  for (auto _ : state) benchmark::DoNotOptimize(vae->encode(x).mean);
  state.SetItemsProcessed(state.iterations() * batch);
  state.counters["per_sample"] = benchmark::Counter(static_cast<double>(state.iterations() * batch),
                                                    benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  set_label(state, graph);
}
BENCHMARK(BM_EncoderInference)
    ->ArgNames({"batch", "threads"})
    ->ArgsProduct({{1, 30}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
