#include "infer/retargeter.h"

// LibTorch before Catch: glog (through c10) defines CHECK, and the last definition wins.
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <vector>

#include "core/error.h"
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
