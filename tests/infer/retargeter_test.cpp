#include "infer/retargeter.h"

// LibTorch before Catch: glog (through c10) defines CHECK, and the last definition wins.
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <vector>

#include "core/error.h"
#include "core/log.h"
#include "models/mesh_vae.h"
#include "tests/infer/infer_test_support.h"

namespace retarget {
namespace {

TEST_CASE("Retargeter: the stages compose to the in-framework pipeline", "[retargeter]") {
  const std::string folder = test::tiny_bundle(test::scratch_dir("infer_retargeter"));
  const LoadedBundle bundle = load_bundle(folder);
  const std::vector<Positions> frames = deformed_frames(test::human_patch(), 5);
  std::vector<const Positions*> human;
  for (const Positions& p : frames) human.push_back(&p);

  for (const bool align : {true, false}) {
    INFO("align_to_rest " << align);
    RetargeterOptions options;
    options.align_to_rest = align;
    Retargeter retargeter(bundle, options);
    CHECK(retargeter.human_vertices() == 143);
    CHECK(retargeter.avatar_vertices() == 146);
    const torch::Tensor x = retargeter.features(human);
    CHECK(x.sizes() == torch::IntArrayRef({5, 143, 9}));
    const torch::Tensor y = retargeter.translate(x);
    CHECK(y.sizes() == torch::IntArrayRef({5, 146, 9}));
    const std::vector<Positions> avatar = retargeter.reconstruct(y);
    REQUIRE(avatar.size() == 5);
    const std::vector<Positions> again = retargeter.retarget(human);
    for (int k = 0; k < 5; ++k) {
      INFO("frame " << k);
      CHECK(test::max_difference(avatar[k], test::expected_output(bundle, frames[k], align)) <= 1e-4);
      CHECK(test::max_difference(again[k], avatar[k]) <= 1e-6);
    }
    // The outputs leave the rest pose and differ between frames (a little: random weights).
    CHECK(test::max_difference(avatar[0], bundle.avatar_rest.vertices) > 1e-3);
    CHECK(test::max_difference(avatar[0], avatar[2]) > 1e-6);
  }
}

TEST_CASE("Retargeter holds the bundle's still avatar vertices at rest", "[retargeter]") {
  const std::string folder = test::tiny_bundle(test::scratch_dir("infer_retargeter_still"));
  LoadedBundle bundle = load_bundle(folder);
  // The lower half of the ball never moves (as a bundle exported from such a dataset says).
  std::vector<int64_t> still;
  for (int v = 0; v < bundle.avatar_rest.vertex_count(); ++v)
    if (bundle.avatar_rest.vertices(v, 1) < 0) still.push_back(v);
  REQUIRE(still.size() > 20);
  bundle.metadata.avatar.still_vertices = still;
  const std::vector<Positions> frames = deformed_frames(test::human_patch(), 2);
  const std::vector<const Positions*> human{&frames[0], &frames[1]};
  Retargeter anchored(bundle);
  RetargeterOptions free_options;
  free_options.anchors = false;
  Retargeter free(bundle, free_options);
  const std::vector<Positions> a = anchored.retarget(human), f = free.retarget(human);
  double anchored_max = 0, free_max = 0;
  for (int64_t v : still) {
    anchored_max = std::max(anchored_max, (a[1].row(v) - bundle.avatar_rest.vertices.row(v)).norm());
    free_max = std::max(free_max, (f[1].row(v) - bundle.avatar_rest.vertices.row(v)).norm());
  }
  CHECK(anchored_max < 1e-9);
  CHECK(free_max > 1e-4);
  // The rest of the mesh still moves.
  CHECK(test::max_difference(a[1], bundle.avatar_rest.vertices) > 1e-3);
}

TEST_CASE("Retargeter's native encoder computes the bundle's scripted forward", "[retargeter]") {
  STATIC_REQUIRE(kNativeNetworkSlope == kMeshVaeSlope);
  const std::vector<Positions> frames = deformed_frames(test::human_patch(), 3);
  const std::vector<const Positions*> human{&frames[0], &frames[1], &frames[2]};
  // Widening (terms first), equal, narrowing (weights first, Clenshaw) and narrowing to one
  // channel; Chebyshev orders 1 to 3.
  // Order 2 also with the encoder skip (models/mesh_vae.h), which the native encoder adds.
  for (const int64_t order : {1, 2, 3, -2}) {
    INFO("order " << order);
    RandomBundleOptions options = test::tiny_bundle_options();
    options.channels = {9, 16, 16, 8, 1};
    options.order = std::abs(order);
    options.encoder_skip = order < 0;
    const std::string folder = test::scratch_dir("infer_retargeter_native_" + std::to_string(order)).string();
    write_random_bundle(test::human_patch(), test::avatar_ball(), folder, options);
    const LoadedBundle bundle = load_bundle(folder);
    Retargeter native(bundle);
    RetargeterOptions scripted_options;
    scripted_options.native_network = false;
    Retargeter scripted(bundle, scripted_options);
    REQUIRE(native.native_network());
    REQUIRE_FALSE(scripted.native_network());
    CHECK(bundle.module.hasattr("human_encoder_skip_weight") == options.encoder_skip);

    const torch::Tensor x = native.features(human);
    torch::jit::Module module = bundle.module;
    c10::InferenceMode inference;
    const torch::Tensor expected = module.run_method("encode_human", x).toTensor();
    const torch::Tensor mean = NativeNetwork::of_bundle(bundle.module)->encode_human(x);
    REQUIRE(mean.sizes() == expected.sizes());
    const double scale = expected.abs().max().item<double>();
    CHECK(scale > 1e-2);
    CHECK((mean - expected).abs().max().item<double>() <= 1e-5 * scale);
    // Each sample as if alone.
    const torch::Tensor alone = NativeNetwork::of_bundle(bundle.module)->encode_human(x.narrow(0, 1, 1));
    CHECK((alone - expected.narrow(0, 1, 1)).abs().max().item<double>() <= 1e-5 * scale);

    const auto network = NativeNetwork::of_bundle(bundle.module);
    REQUIRE(network->decodes());
    const torch::Tensor code = module.run_method("translate", expected).toTensor();
    const torch::Tensor decoded = module.run_method("decode_avatar", code).toTensor();
    CHECK((network->decode_avatar(code) - decoded).abs().max().item<double>() <=
          1e-5 * decoded.abs().max().item<double>());

    const torch::Tensor y = native.translate(x), y_scripted = scripted.translate(x);
    REQUIRE(y.sizes() == y_scripted.sizes());
    CHECK((y - y_scripted).abs().max().item<double>() <= 1e-5 * y_scripted.abs().max().item<double>());
    CHECK_THROWS_WITH(native.translate(x.narrow(1, 0, 100)), Catch::Contains("expected x of shape [B, 143, 9]"));
  }
  // A module without the human encoder's tensors has no native encoder.
  CHECK(NativeNetwork::of_bundle(torch::jit::Module("__torch__.Empty")) == nullptr);
}

// Reduced-precision products against float32 on the paper's widths (the small patch): the avatar
// features' error as a share of the normaliser's range, and the codes' relative to their largest.
struct PrecisionBound {
  NetworkPrecision precision;
  bool cpu_has;  // the CPU feature it needs
  double features, codes;
};

TEST_CASE("Retargeter's reduced-precision products stay near float32's", "[retargeter]") {
  // bfloat16: an 8-bit significand (relative 2^-9 per rounding) through five graph convs; int8:
  // each activation row in 255 levels of its own largest value, each weight row likewise.
  const PrecisionBound bounds[] = {{NetworkPrecision::bfloat16, __builtin_cpu_supports("avx512bf16") != 0, 1e-3, 5e-3},
                                   {NetworkPrecision::int8, __builtin_cpu_supports("avx512vnni") != 0, 2e-2, 5e-2}};
  RandomBundleOptions options = test::tiny_bundle_options();
  options.channels = {9, 128, 64, 64, 64, 1};
  const std::string folder = test::scratch_dir("infer_retargeter_precision").string();
  write_random_bundle(test::human_patch(), test::avatar_ball(), folder, options);
  const LoadedBundle bundle = load_bundle(folder);
  Retargeter f32(bundle);
  CHECK(f32.precision() == NetworkPrecision::float32);
  const std::vector<Positions> frames = deformed_frames(test::human_patch(), 4);
  const std::vector<const Positions*> human{&frames[0], &frames[1], &frames[2], &frames[3]};
  const torch::Tensor x = f32.features(human);
  const torch::Tensor y = f32.translate(x);
  const torch::Tensor code = NativeNetwork::of_bundle(bundle.module)->encode_human(x);
  // The raw avatar features' spread per (vertex, feature) sets the scale: the normaliser's range.
  const torch::Tensor lo = bundle.module.attr("avatar_normaliser_min").toTensor();
  const torch::Tensor hi = bundle.module.attr("avatar_normaliser_max").toTensor();
  for (const PrecisionBound& bound : bounds) {
    INFO(to_string(bound.precision));
    RetargeterOptions reduced_options;
    reduced_options.precision = bound.precision;
    Retargeter reduced(bundle, reduced_options);
    if (reduced.precision() != bound.precision) {
      // Falls back to float32, and only where the CPU lacks the feature.
      CHECK(reduced.precision() == NetworkPrecision::float32);
      CHECK_FALSE(bound.cpu_has);
      CHECK_FALSE(network_precision_available(bound.precision));
      continue;
    }
    const double error = ((reduced.translate(x) - y).abs() / (hi - lo)).max().item<double>();
    const torch::Tensor reduced_code = NativeNetwork::of_bundle(bundle.module, bound.precision)->encode_human(x);
    const double code_error = (reduced_code - code).abs().max().item<double>() / code.abs().max().item<double>();
    INFO("feature error " << error << " of the normaliser's range, code error " << code_error);
    CHECK(error > 0);  // the products did run in the reduced precision
    CHECK(error <= bound.features);
    CHECK(code_error <= bound.codes);
  }
}

TEST_CASE("Retargeter says which network and kernels run, and warns when a precision falls back", "[retargeter]") {
  const std::string folder = test::tiny_bundle(test::scratch_dir("infer_retargeter_says"));
  const LoadedBundle bundle = load_bundle(folder);
  for (const bool native : {true, false})
    for (const NetworkPrecision precision :
         {NetworkPrecision::float32, NetworkPrecision::bfloat16, NetworkPrecision::int8}) {
      std::vector<std::pair<log::Level, std::string>> said;
      const log::Sink previous =
          log::set_sink([&](log::Level level, const std::string& m) { said.emplace_back(level, m); });
      RetargeterOptions options;
      options.native_network = native;
      options.precision = precision;
      const Retargeter retargeter(bundle, options);
      log::set_sink(previous);
      const auto said_at = [&](log::Level level, const std::string& text) {
        for (const auto& [l, m] : said)
          if (l == level && m.find(text) != std::string::npos) return true;
        return false;
      };
      INFO("native " << native << ", asked " << to_string(precision));
      REQUIRE(retargeter.native_network() == native);
      if (!native) {
        CHECK(said_at(log::Level::info, "network: the bundle's TorchScript"));
        continue;
      }
      const NetworkPrecision ran = retargeter.precision();
      CHECK(said_at(log::Level::info,
                    std::string("network: native, ") + to_string(ran) + " products: " + network_products_kernel(ran)));
      CHECK(said_at(log::Level::warn, std::string("precision ") + to_string(precision)) == (ran != precision));
      CHECK((ran == precision) == network_precision_available(precision));
    }
}

TEST_CASE("the benchmarks name the routine each precision's products call, and say when the CPU lacks it",
          "[retargeter]") {
  const std::string f32 = network_products_kernel(NetworkPrecision::float32);
  CHECK((f32 == "oneDNN dnnl_sgemm" || f32 == "LibTorch mm"));
  for (const auto& [precision, routine] : {std::pair{NetworkPrecision::bfloat16, "dnnl_gemm_bf16bf16f32"},
                                           std::pair{NetworkPrecision::int8, "dnnl_gemm_u8s8s32"}}) {
    const std::string kernel = network_products_kernel(precision);
    INFO(kernel);
    CHECK(kernel.find(routine) != std::string::npos);
    CHECK((kernel.find("not on this CPU") != std::string::npos) == !network_precision_available(precision));
  }
  // The other loops: the AVX-512 ones exactly where the CPU has AVX-512.
  CHECK(network_loops_kernel() ==
        (__builtin_cpu_supports("avx512f") ? "AVX-512 intrinsics" : "compiler-vectorised loops (AVX2 or baseline)"));
}

TEST_CASE("Retargeter refuses meshes of another vertex count", "[retargeter]") {
  const std::string folder = test::tiny_bundle(test::scratch_dir("infer_retargeter_refuses"));
  Retargeter retargeter(load_bundle(folder));
  const Positions wrong = test::avatar_ball().vertices;
  CHECK_THROWS_WITH(retargeter.features({&wrong}), Catch::Contains("146 vertices") && Catch::Contains("143"));
  RetargeterOptions bad;
  bad.threads = -1;
  CHECK_THROWS_WITH(Retargeter(load_bundle(folder), bad), Catch::Contains("retargeter.threads"));
}

}  // namespace
}  // namespace retarget
