#include "eval/vae_evaluation.h"

#include <catch2/catch.hpp>
#include <filesystem>

#include "data/dataset.h"
#include "geometry/metrics.h"
#include "geometry/rigid_alignment.h"
#include "test_support.h"
#include "tiny_data.h"
#include "train/vae_run.h"

using namespace retarget;
using namespace retarget::test;
namespace fs = std::filesystem;

namespace {

// tiny_rig(7) (64 vertices) whose controllers never move the half of the patch with x < 1.
Rig half_still_rig() {
  Rig rig = tiny_rig(7);
  for (Controller& c : rig.controllers)
    for (int v = 0; v < rig.neutral.vertex_count(); ++v)
      if (rig.neutral.vertices(v, 0) < 1.0) c.offset.row(v).setZero();
  return rig;
}

// An avatar dataset of that rig, 30 samples, 9 held out (built once per test binary).
std::string half_still_dataset() {
  static const std::string folder = build_tiny_avatar_dataset("vae_evaluation_avatar", half_still_rig(), 30, 0.3, 5);
  return folder;
}

std::string human_dataset() {
  static const std::string folder = build_tiny_human_dataset("vae_evaluation_human", 6, 2, 3);
  return folder;
}

// An untrained VAE for the dataset (its figures do not matter here; the trivial answers do).
MeshVae untrained_vae(const Dataset& d) {
  MeshVaeOptions model(d.vertex_count());
  model.channels({9, 4, 1}).hidden(8).latent(2).order(2);
  torch::manual_seed(1);
  return build_mesh_vae(d.rest, model);
}

}  // namespace

TEST_CASE("the neutral answer scores what the truth's distance from the rest is, after alignment", "[vae_evaluation]") {
  const Dataset d = load_dataset(half_still_dataset());
  MeshVae vae = untrained_vae(d);
  const VaeEvaluation r = evaluate_vae(*vae, d);
  REQUIRE(r.ground_truth == "rig meshes");
  REQUIRE(r.unit == "mm");
  REQUIRE(r.trivial.size() == 1);  // avatars: no mean-expression answer
  const TrivialScore* neutral = r.trivial_answer("neutral");
  REQUIRE(neutral != nullptr);
  CHECK(r.trivial_answer("mean_expression") == nullptr);

  // By hand: each test sample's rig mesh, the rest aligned onto it, mean distance in mm.
  const Rig rig = load_rig(d.source);
  const double mm = millimetres_per_unit(d.rest.vertices, d.eyes);
  double mean = 0, mean_of_max = 0, l1 = 0;
  const torch::Tensor zero = d.normaliser.normalise(torch::zeros({d.vertex_count(), 9}));
  for (int64_t row : d.test) {
    Eigen::VectorXd w(d.weights.size(1));
    for (int64_t j = 0; j < w.size(); ++j) w(j) = d.weights[row][j].item<double>();
    const Positions truth = rig.evaluate(w);
    const Positions aligned = rigid_alignment(d.rest.vertices, truth).apply(d.rest.vertices);
    const Eigen::VectorXd distance = (aligned - truth).rowwise().norm() * mm;
    mean += distance.mean();
    mean_of_max += distance.maxCoeff();
    l1 += (d.normaliser.normalise(d.features[row]) - zero).abs().mean().item<double>();
  }
  const auto n = static_cast<double>(d.test.size());
  CHECK(neutral->mean > 0);
  CHECK(neutral->mean == Approx(mean / n).epsilon(1e-9));
  CHECK(neutral->mean_of_max == Approx(mean_of_max / n).epsilon(1e-9));
  CHECK(neutral->feature_l1 == Approx(l1 / n).epsilon(1e-5));
  CHECK(r.fraction_of_neutral == Approx(r.mean / neutral->mean));
  CHECK(r.moving_fraction_of_neutral == Approx(r.moving_mean / neutral->moving_mean));
}

TEST_CASE("errors over the moving vertices leave out the part of the mesh that never moves", "[vae_evaluation]") {
  const Dataset d = load_dataset(half_still_dataset());
  MeshVae vae = untrained_vae(d);
  const VaeEvaluation r = evaluate_vae(*vae, d);
  CHECK(r.footprint == "rig controllers");
  // Half the patch is still: some vertices move, not all.
  CHECK(r.moving_vertices > 0);
  CHECK(r.moving_vertices < r.vertices);
  const TrivialScore& neutral = *r.trivial_answer("neutral");
  CHECK(neutral.moving_mean >= neutral.mean);
  CHECK(neutral.moving_mean > 1.2 * neutral.mean);  // the still half dilutes the all-vertex mean
}

TEST_CASE("a human VAE is scored beside the neutral face and the mean expression", "[vae_evaluation]") {
  const Dataset d = load_dataset(human_dataset());
  MeshVae vae = untrained_vae(d);
  const VaeEvaluation r = evaluate_vae(*vae, d);
  CHECK(r.footprint == "ground-truth meshes");
  REQUIRE(r.trivial.size() == 2);
  CHECK(r.trivial[0].name == "neutral");
  CHECK(r.trivial[1].name == "mean_expression");
  for (const TrivialScore& t : r.trivial) {
    INFO(t.name);
    CHECK(std::isfinite(t.mean));
    CHECK(t.mean_of_max >= t.mean);
    // Every vertex of the tiny face moves: the two means are one sum in two orders, equal up to
    // rounding.
    CHECK(t.moving_mean >= t.mean * (1 - 1e-12));
    CHECK(t.feature_l1 > 0);
  }
  // One of the recipes is the neutral expression itself, the others move the face: the mean
  // expression sits between them, not on any, so neither trivial answer is exact.
  CHECK(r.trivial[0].mean > 0);
  CHECK(r.trivial[1].mean > 0);
  CHECK(r.fraction_of_neutral == Approx(r.mean / r.trivial[0].mean));
}
