#include "geometry/rig_weight_fit.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "bump_rig.h"
#include "core/error.h"
#include "test_support.h"

using Catch::Contains;
using namespace retarget;

namespace rig_weight_fit_test {  // named: a unity batch shares one anonymous namespace

// A ball of 2 + 11 x 16 = 178 vertices (radius 1) with 6 overlapping controllers: smooth bumps
// along the normal around different spots (two of them in ranges other than [0, 1]) and a
// sideways shear of the upper half (+y). The back (-z) moves for no controller.
Rig small_rig() {
  Rig rig;
  rig.name = "ball";
  rig.source = "ball/rig.yaml";
  rig.neutral = uv_sphere(12, 16);
  const Positions& n = rig.neutral.vertices;
  const std::vector<Eigen::RowVector3d> spots{
      {0, 0.6, 0.8}, {0.5, 0.5, 0.7}, {-0.5, 0.5, 0.7}, {0, 0, 1}, {0.7, 0, 0.7}};
  const std::vector<std::pair<double, double>> ranges{{0, 1}, {0, 1}, {-1, 1}, {0, 2}, {0, 1}};
  for (size_t k = 0; k < spots.size(); ++k)
    rig.controllers.push_back(test::bump_controller("bump" + std::to_string(k), n, 1.0, spots[k], 0.2, 0.3, ranges[k]));
  Controller shear;
  shear.name = "shear";
  shear.offset = Positions::Zero(n.rows(), 3);
  for (Eigen::Index i = 0; i < n.rows(); ++i) shear.offset(i, 0) = 0.15 * std::max(0.0, n(i, 1));
  rig.controllers.push_back(std::move(shear));
  return rig;
}

Eigen::VectorXd random_weights(const Rig& rig, std::mt19937& random) {
  Eigen::VectorXd w(rig.controller_count());
  for (int k = 0; k < rig.controller_count(); ++k)
    w(k) = std::uniform_real_distribution<double>(rig.controllers[k].min, rig.controllers[k].max)(random);
  return w;
}

}  // namespace rig_weight_fit_test

TEST_CASE("RigWeightFit recovers the weights of the rig's own expressions", "[rig_weight_fit]") {
  const Rig rig = rig_weight_fit_test::small_rig();
  std::mt19937 random(3);
  const RigWeightFit exact(rig);
  RigWeightFitOptions ridged;
  ridged.ridge = 1e-3;
  const RigWeightFit regularised(rig, ridged);
  double exact_error = 0, ridge_error = 0;
  constexpr int kTrials = 20;
  for (int t = 0; t < kTrials; ++t) {
    const Eigen::VectorXd w = rig_weight_fit_test::random_weights(rig, random);
    const Positions mesh = rig.evaluate(w);
    const Eigen::VectorXd a = exact.fit(mesh), b = regularised.fit(mesh);
    exact_error += (a - w).cwiseAbs().mean() / kTrials;
    ridge_error += (b - w).cwiseAbs().mean() / kTrials;
    CHECK(exact.residual(mesh, a) < 1e-6);
    CHECK(regularised.residual(mesh, b) < 0.01);
  }
  CHECK(exact_error < 1e-5);
  CHECK(ridge_error <= 0.02);
  // The back moves for no controller; the front does.
  const std::vector<int>& moving = exact.moving_vertices();
  CHECK(moving.size() < static_cast<size_t>(rig.neutral.vertex_count()));
  CHECK(moving.front() == 0);                             // the front pole (+z)
  CHECK(moving.back() < rig.neutral.vertex_count() - 1);  // the back pole (-z) is still
}

TEST_CASE("RigWeightFit keeps every weight within its controller's range", "[rig_weight_fit]") {
  const Rig rig = rig_weight_fit_test::small_rig();
  Eigen::VectorXd beyond(rig.controller_count());
  beyond << 1.6, -0.5, -1.8, 2.7, 0.4, 3.0;  // outside the ranges except bump4
  const Eigen::VectorXd w = RigWeightFit(rig).fit(rig.evaluate(beyond));
  for (int k = 0; k < rig.controller_count(); ++k) {
    INFO(rig.controllers[k].name);
    CHECK(w(k) >= rig.controllers[k].min);
    CHECK(w(k) <= rig.controllers[k].max);
  }
  CHECK(w(5) == 1.0);  // the shear, far beyond its range, ends at its bound
}

TEST_CASE("RigWeightFit: the smoothness term pulls towards the previous frame", "[rig_weight_fit]") {
  const Rig rig = rig_weight_fit_test::small_rig();
  std::mt19937 random(5);
  const Eigen::VectorXd truth = rig_weight_fit_test::random_weights(rig, random),
                        previous = rig_weight_fit_test::random_weights(rig, random);
  Positions mesh = rig.evaluate(truth);
  std::normal_distribution<double> noise(0, 0.01);
  for (Eigen::Index i = 0; i < mesh.size(); ++i) mesh.data()[i] += noise(random);

  RigWeightFitOptions plain_options;
  plain_options.ridge = 1e-3;
  const RigWeightFit plain(rig, plain_options);
  const Eigen::VectorXd free = plain.fit(mesh);
  // Smoothness 0 with a previous frame is the plain fit (to the descent's tolerance).
  CHECK((plain.fit(mesh, previous) - free).cwiseAbs().maxCoeff() < 1e-6);
  // No previous frame: the plain fit, whatever the smoothness.
  RigWeightFitOptions smooth_options = plain_options;
  smooth_options.smoothness = 1.0;
  const RigWeightFit smooth(rig, smooth_options);
  CHECK((smooth.fit(mesh, Eigen::VectorXd()) - free).cwiseAbs().maxCoeff() < 1e-6);

  // The distance to the previous frame shrinks as the smoothness grows, and the mesh's own
  // residual grows: a trade-off, not a different answer.
  double last_distance = (free - previous).norm(), last_residual = plain.residual(mesh, free);
  for (const double s : {0.1, 1.0, 10.0, 1000.0}) {
    INFO("smoothness " << s);
    RigWeightFitOptions o = plain_options;
    o.smoothness = s;
    const RigWeightFit fit(rig, o);
    const Eigen::VectorXd w = fit.fit(mesh, previous);
    const double distance = (w - previous).norm(), residual = fit.residual(mesh, w);
    CHECK(distance < last_distance);
    CHECK(residual >= last_residual - 1e-12);
    last_distance = distance;
    last_residual = residual;
  }
  CHECK(last_distance < 0.01);  // s = 1000: essentially the previous frame
}

TEST_CASE("RigWeightFit: residual is the mean distance over the moving vertices", "[rig_weight_fit]") {
  const Rig rig = rig_weight_fit_test::small_rig();
  const RigWeightFit fit(rig);
  const Eigen::VectorXd w = Eigen::VectorXd::Constant(rig.controller_count(), 0.5);
  Positions mesh = rig.evaluate(w);
  CHECK(fit.residual(mesh, w) == Approx(0).margin(1e-12));
  mesh.col(2).array() += 0.03;  // every vertex 0.03 off
  CHECK(fit.residual(mesh, w) == Approx(0.03));
  mesh.row(mesh.rows() - 1).array() += 5;  // a still vertex (the back pole) does not count
  CHECK(fit.residual(mesh, w) == Approx(0.03));
}

TEST_CASE("RigWeightFit refuses bad options and sizes, naming them", "[rig_weight_fit]") {
  const Rig rig = rig_weight_fit_test::small_rig();
  RigWeightFitOptions o;
  o.smoothness = -1;
  CHECK_THROWS_WITH(RigWeightFit(rig, o), Contains("rig_weight_fit.smoothness") && Contains(">= 0"));
  o.smoothness = NAN;
  CHECK_THROWS_WITH(RigWeightFit(rig, o), Contains("rig_weight_fit.smoothness"));
  o = {};
  o.ridge = INFINITY;
  CHECK_THROWS_WITH(RigWeightFit(rig, o), Contains("rig_weight_fit.ridge"));
  const RigWeightFit fit(rig);
  CHECK_THROWS_WITH(fit.fit(Positions::Zero(5, 3)), Contains("ball/rig.yaml") && Contains("5 vertices"));
  CHECK_THROWS_WITH(fit.fit(rig.neutral.vertices, Eigen::VectorXd::Zero(2)),
                    Contains("2 previous weights") && Contains("6 controllers"));
  CHECK_THROWS_WITH(fit.residual(rig.neutral.vertices, Eigen::VectorXd::Zero(3)), Contains("3 weights"));
}
