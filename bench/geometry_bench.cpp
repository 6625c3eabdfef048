// Geometry benchmarks on an ~11k-vertex face: DR features, reconstruction, one
// deformation-transfer solve, and OBJ reading. Uses the real ICT face when
// RETARGET_SHARED_DATA (default: <source>/../shared/data) has it, otherwise a synthetic
// 11,202-vertex sphere with a smooth bulge as the "expression".
#include <benchmark/benchmark.h>
#include <omp.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <vector>

#include "bench/shared_data.h"
#include "geometry/deformation_transfer.h"
#include "geometry/dr_features.h"
#include "geometry/dr_pack_lanes.h"
#include "geometry/mesh_io.h"
#include "geometry/primitive_meshes.h"
#include "geometry/reconstruction.h"
#include "geometry/rotation.h"

namespace {

using namespace retarget;
namespace fs = std::filesystem;

struct Fixture {
  Mesh rest, target;  // target: another identity (ICT) or a scaled, bumped sphere
  Positions expression;
  std::string obj_path;  // a mesh file to time reading
  std::string name;
};

const Fixture& fixture() {
  static const Fixture f = [] {
    Fixture f;
    const fs::path ict = retarget::bench::shared_data() / "ict-face";
    if (fs::exists(ict / "neutral.obj")) {
      f.name = "ICT face";
      f.obj_path = (ict / "neutral.obj").string();
      f.rest = read_mesh(f.obj_path);
      f.target = read_mesh((ict / "identities" / "identity003.obj").string());
      f.expression = read_mesh((ict / "expressions" / "jawOpen.obj").string()).vertices;
    } else {
      f.name = "synthetic sphere";
      f.rest = uv_sphere(100, 112, 10.0);
      f.target = f.rest;
      f.target.vertices.col(1) *= 1.2;
      f.expression = f.rest.vertices;
      for (int i = 0; i < f.rest.vertex_count(); ++i) {
        const double z = f.rest.vertices(i, 2);
        f.expression(i, 2) += 1.5 * std::exp(-(10 - z) * (10 - z) / 8.0);
      }
      f.obj_path = (fs::temp_directory_path() / "retarget_bench_sphere.obj").string();
      write_mesh(f.obj_path, f.rest);
    }
    return f;
  }();
  return f;
}

// lanes: the DR benchmarks also name the vector lanes that ran (geometry/dr_pack_lanes.h).
void set_label(benchmark::State& state, const char* lanes = nullptr) {
  state.SetLabel(fixture().name + ", " + std::to_string(fixture().rest.vertex_count()) + " vertices" +
                 (lanes ? std::string(", DR lanes: ") + lanes : std::string()));
}

void BM_DrFeatures(benchmark::State& state) {
  DrOptions options;
  options.threads = static_cast<int>(state.range(0));
  const DrFeatures features(fixture().rest, options);
  DrFeatureMatrix out(fixture().rest.vertex_count(), kDrWidth);
  for (auto _ : state) {
    features.compute(fixture().expression, out.data());
    benchmark::DoNotOptimize(out.data());
  }
  set_label(state, dr_lanes_name());
}
BENCHMARK(BM_DrFeatures)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_DrFeaturesSetup(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(DrFeatures(fixture().rest));
  set_label(state);
}
BENCHMARK(BM_DrFeaturesSetup)->Unit(benchmark::kMillisecond);

// The polar decompositions and rotation logs of DR features alone, on the fixture's expression's
// gradients (each vertex's T from its features): arg 0 one at a time (polar_decomposition, pack_dr),
// 1-3 in vector lanes (geometry/dr_pack_lanes.h: baseline, AVX2, AVX-512; skipped where the CPU
// lacks it). One thread.
void BM_DrPack(benchmark::State& state) {
  const DrFeatureMatrix features = DrFeatures(fixture().rest).compute(fixture().expression);
  std::vector<Eigen::Matrix3d> gradients(features.rows());
  for (Eigen::Index i = 0; i < features.rows(); ++i) gradients[i] = unpack_dr(features.row(i).data());
  const DrLanes lanes[] = {DrLanes::automatic, DrLanes::baseline, DrLanes::avx2, DrLanes::avx512};
  const int64_t version = state.range(0);
  if (version > 0 && !dr_lanes_available(lanes[version])) {
    state.SkipWithError("this CPU does not run these lanes");
    return;
  }
  DrFeatureMatrix out(features.rows(), kDrWidth);
  const int count = static_cast<int>(gradients.size());
  for (auto _ : state) {
    if (version == 0) {
      for (int i = 0; i < count; ++i) {
        const PolarDecomposition p = polar_decomposition(gradients[i]);
        pack_dr(p.rotation, p.stretch, out.data() + static_cast<size_t>(i) * kDrWidth);
      }
    } else {
      pack_dr_lanes(gradients.data(), count, out.data(), lanes[version]);
    }
    benchmark::DoNotOptimize(out.data());
  }
  set_label(state, version == 0 ? "none (one at a time)" : dr_lanes_name(lanes[version]));
}
BENCHMARK(BM_DrPack)->ArgName("lanes")->DenseRange(0, 3)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Reconstruction(benchmark::State& state) {
  const DrFeatureMatrix features = DrFeatures(fixture().rest).compute(fixture().expression);
  const Reconstruction reconstruction(fixture().rest);
  for (auto _ : state) benchmark::DoNotOptimize(reconstruction.reconstruct(features));
  set_label(state);
  state.counters["factor_nnz"] = static_cast<double>(reconstruction.factor_nonzeros());
}
BENCHMARK(BM_Reconstruction)->Unit(benchmark::kMillisecond);

void BM_ReconstructionFactorisation(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(Reconstruction(fixture().rest));
  set_label(state);
}
BENCHMARK(BM_ReconstructionFactorisation)->Unit(benchmark::kMillisecond);

const DeformationTransfer& transfer() {
  static const DeformationTransfer dt = [] {
    std::vector<LandmarkPair> landmarks;
    const int n = fixture().rest.vertex_count();
    for (int k = 0; k < 40; ++k) landmarks.push_back({k * (n / 40), k * (n / 40)});
    return DeformationTransfer(fixture().rest, fixture().target, landmarks);
  }();
  return dt;
}

void BM_DeformationTransferSolve(benchmark::State& state) {
  const DeformationTransfer& dt = transfer();
  for (auto _ : state) benchmark::DoNotOptimize(dt.transfer(fixture().expression));
  set_label(state);
}
BENCHMARK(BM_DeformationTransferSolve)->Unit(benchmark::kMillisecond);

void BM_DeformationTransferSetup(benchmark::State& state) {
  std::vector<LandmarkPair> landmarks;
  const int n = fixture().rest.vertex_count();
  for (int k = 0; k < 40; ++k) landmarks.push_back({k * (n / 40), k * (n / 40)});
  for (auto _ : state) benchmark::DoNotOptimize(DeformationTransfer(fixture().rest, fixture().target, landmarks));
  set_label(state);
}
BENCHMARK(BM_DeformationTransferSetup)->Unit(benchmark::kMillisecond)->Iterations(2);

void BM_ReadObj(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(read_mesh(fixture().obj_path));
  set_label(state);
}
BENCHMARK(BM_ReadObj)->Unit(benchmark::kMillisecond);

// A computed face as this project writes meshes (write_mesh: shortest round-trip numbers, 16-17
// digits, where BM_ReadObj's file has the ICT model's 6): the expression scaled by 1 + 1e-7, read
// on `threads` OpenMP threads. What retarget-infer reads when its inputs are another run's
// outputs, and what its benchmark (BM_InferBatch) reads.
void BM_ReadObjWritten(benchmark::State& state) {
  static const std::string path = [] {
    const std::string p = (fs::temp_directory_path() / "retarget_bench_written.obj").string();
    Mesh mesh = fixture().rest;
    mesh.vertices = fixture().expression * (1 + 1e-7);
    write_mesh(p, mesh);
    return p;
  }();
  const int threads = static_cast<int>(state.range(0));
  const int before = omp_get_max_threads();
  omp_set_num_threads(threads);
  for (auto _ : state) benchmark::DoNotOptimize(read_mesh(path));
  omp_set_num_threads(before);
  set_label(state);
}
BENCHMARK(BM_ReadObjWritten)->ArgName("threads")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

}  // namespace
