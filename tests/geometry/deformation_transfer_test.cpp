#include "geometry/deformation_transfer.h"

#include <omp.h>

#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <string>

#include "core/error.h"
#include "geometry/closest_point.h"
#include "geometry/synthetic_deformations.h"
#include "test_support.h"

using namespace retarget;

namespace {

double bbox_diagonal(const Positions& V) { return (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm(); }

double mean_error(const Positions& a, const Positions& b) { return (a - b).rowwise().norm().mean(); }

// The same grid as test::bumpy_patch(n) with another height field: the "other person".
Mesh other_patch(int n) {
  return test::quad_grid(n, n, 2.0, 2.0, [](double x, double y) {
    const double dx = x - 0.8, dy = y - 1.1;
    return 0.45 * std::exp(-(dx * dx + dy * dy) / 0.7) + 0.08 * x - 0.04 * std::cos(2 * y);
  });
}

// A bump raised near (1.2, 0.9) and the upper half sheared along x, as a function of the
// grid coordinates (x, y), so that it means the same thing on any patch over [0, 2]^2.
Positions expression(const Positions& V) {
  Positions out = V;
  for (int i = 0; i < V.rows(); ++i) {
    const double x = V(i, 0), y = V(i, 1);
    const double r2 = (x - 1.2) * (x - 1.2) + (y - 0.9) * (y - 0.9);
    out(i, 2) += 0.15 * std::exp(-r2 / 0.1);
    out(i, 0) += 0.08 * smoothstep(0.8, 1.6, y);
  }
  return out;
}

// ~40 landmarks on a 25 x 25 vertex grid, each vertex paired with itself.
std::vector<LandmarkPair> grid_landmarks(int n) {
  std::vector<LandmarkPair> landmarks;
  for (int j : {0, 5, 10, 14, 19, n})
    for (int i = 0; i <= n; i += 4) landmarks.push_back({j * (n + 1) + i, j * (n + 1) + i});
  return landmarks;
}

// Sphere vertex index of ring i (1..rings-1, 0 = north pole) and segment j.
int sphere_vertex(int rings, int segments, int i, int j) {
  if (i == 0) return 0;
  if (i == rings) return 2 + (rings - 1) * segments - 1;
  return 1 + (i - 1) * segments + j;
}

// Landmarks where a (18 x 24) and a (12 x 16) UV sphere have vertices in the same direction.
std::vector<LandmarkPair> sphere_landmarks() {
  std::vector<LandmarkPair> landmarks{{sphere_vertex(18, 24, 0, 0), sphere_vertex(12, 16, 0, 0)},
                                      {sphere_vertex(18, 24, 18, 0), sphere_vertex(12, 16, 12, 0)}};
  for (int m = 1; m <= 5; ++m)
    for (int k = 0; k < 8; ++k)
      landmarks.push_back({sphere_vertex(18, 24, 3 * m, 3 * k), sphere_vertex(12, 16, 2 * m, 2 * k)});
  return landmarks;
}

Positions transform(const Positions& V, const Eigen::Matrix3d& A, const Eigen::Vector3d& centre,
                    const Eigen::Vector3d& shift) {
  Positions out = ((V.rowwise() - centre.transpose()) * A.transpose()).rowwise() + (centre + shift).transpose();
  return out;
}

// Runs `body` and returns the message of the retarget::Error it throws ("" if none).
template <typename Body>
std::string error_of(Body body) {
  try {
    body();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("human to human: same topology, another shape", "[deformation_transfer]") {
  const Mesh source = test::bumpy_patch(24);
  Mesh target = other_patch(24);
  target.vertices.rowwise() += Eigen::RowVector3d(0.3, -0.2, 0.5);
  const auto landmarks = grid_landmarks(24);
  const DeformationTransfer dt(source, target, landmarks);
  const double diagonal = bbox_diagonal(target.vertices);

  SECTION("the undeformed source gives the target rest back") {
    const Positions same = dt.transfer(source.vertices);
    // Measured 1.4e-14.
    CHECK((same - target.vertices).cwiseAbs().maxCoeff() < 1e-10 * diagonal);
  }
  SECTION("a smooth expression lands as the same displacement") {
    const Positions source_expression = expression(source.vertices);
    const Positions result = dt.transfer(source_expression);
    const Positions truth = target.vertices + (source_expression - source.vertices);
    const double displacement = (source_expression - source.vertices).rowwise().norm().mean();
    const double error = mean_error(result, truth);
    // Measured 0.20% of the diagonal and 14% of the mean displacement: the two surfaces
    // tilt differently under the bump, and gradients act in the world frame.
    CHECK(error < 0.01 * diagonal);
    CHECK(error < 0.25 * displacement);
  }
}

TEST_CASE("a target of the same shape, moved, gets the source expression exactly", "[deformation_transfer]") {
  const Mesh source = test::bumpy_patch(12);
  Mesh target = source;
  target.vertices.rowwise() += Eigen::RowVector3d(1, -2, 0.5);
  std::vector<LandmarkPair> landmarks;
  for (int j = 0; j <= 12; j += 3)
    for (int i = 0; i <= 12; i += 3) landmarks.push_back({j * 13 + i, j * 13 + i});
  const DeformationTransfer dt(source, target, landmarks);
  // Each triangle is paired with itself only.
  CHECK(dt.triangle_pairs().size() == static_cast<size_t>(source.triangle_count()));
  for (const auto& [s, t] : dt.triangle_pairs()) CHECK(s == t);
  const Positions source_expression = expression(source.vertices);
  const Positions result = dt.transfer(source_expression);
  const Positions truth = target.vertices + (source_expression - source.vertices);
  CHECK((result - truth).cwiseAbs().maxCoeff() < 1e-10);
}

TEST_CASE("different topologies: a rigid motion and a uniform scale carry over", "[deformation_transfer]") {
  const Mesh source = test::uv_sphere(18, 24, 1.0);
  const Eigen::Vector3d target_shift(0.2, 0.1, -0.3);
  Mesh target = test::uv_sphere(12, 16, 1.3);
  target.vertices.rowwise() += target_shift.transpose();
  const DeformationTransfer dt(source, target, sphere_landmarks());
  CHECK(dt.report().prealignment_scale == Approx(1.3));
  const double diagonal = bbox_diagonal(target.vertices);

  // In the target's frame a source map p -> A (p - o) + o + t reads
  // q -> A (q - o') + o' + 1.3 t with o' = 1.3 o + shift.
  const Eigen::Vector3d o(0.2, -0.4, 0.1), t(0.3, 0.2, -0.1);
  const Eigen::Vector3d o_target = 1.3 * o + target_shift;
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 2, 0.5).normalized()).toRotationMatrix();
  const Eigen::Matrix3d scale = 1.25 * Eigen::Matrix3d::Identity();
  for (const Eigen::Matrix3d& A : {rotation, scale}) {
    const Positions result = dt.transfer(transform(source.vertices, A, o, t));
    const Positions truth = transform(target.vertices, A, o_target, 1.3 * t);
    const double max_error = (result - truth).rowwise().norm().maxCoeff();
    // Every gradient is A, so the shape is exact; the translation comes from corresponding
    // points on the source surface, exact here because both spheres are symmetric.
    // Measured: 2e-15 of the diagonal for both.
    const Positions centred_result = result.rowwise() - result.colwise().mean();
    const Positions centred_truth = truth.rowwise() - truth.colwise().mean();
    CHECK((centred_result - centred_truth).cwiseAbs().maxCoeff() < 1e-9 * diagonal);
    CHECK(max_error < 1e-9 * diagonal);
  }
}

TEST_CASE("the fitted source lies on the target and meets the landmarks", "[deformation_transfer]") {
  const Mesh source = test::uv_sphere(18, 24, 1.0);
  Mesh target = test::uv_sphere(12, 16, 1.3);
  target.vertices.rowwise() += Eigen::RowVector3d(0.2, 0.1, -0.3);
  const auto landmarks = sphere_landmarks();
  const double diagonal = bbox_diagonal(target.vertices);
  const ClosestSurfacePoint surface(target.vertices, target.triangles);
  auto mean_distance = [&](const Positions& V) {
    double sum = 0;
    for (int i = 0; i < V.rows(); ++i) sum += std::sqrt(surface.closest(V.row(i).transpose()).squared_distance);
    return sum / V.rows();
  };

  SECTION("hard landmarks") {
    const DeformationTransfer dt(source, target, landmarks);
    const Positions& fitted = dt.fitted_source();
    REQUIRE(fitted.rows() == source.vertex_count());
    for (const auto& l : landmarks) CHECK(fitted.row(l.source) == target.vertices.row(l.target));
    CHECK(mean_distance(fitted) < 1e-4 * diagonal);  // measured 2e-6
    CHECK(dt.report().mean_distance == Approx(mean_distance(fitted)));
    CHECK(dt.report().steps.size() == DeformationTransferOptions{}.closest_point_weights.size());
    CHECK(dt.report().fallback_target_triangles == 0);
    CHECK(dt.report().identity_target_triangles == 0);
    // Each target triangle is paired.
    std::vector<char> paired(target.triangle_count(), 0);
    for (const auto& [s, t] : dt.triangle_pairs()) paired[t] = 1;
    CHECK(std::count(paired.begin(), paired.end(), 0) == 0);
  }
  SECTION("soft landmarks") {
    DeformationTransferOptions options;
    options.landmark_weight = 1000;
    const DeformationTransfer dt(source, target, landmarks, options);
    const Positions& fitted = dt.fitted_source();
    double worst = 0;
    for (const auto& l : landmarks)
      worst = std::max(worst, (fitted.row(l.source) - target.vertices.row(l.target)).norm());
    CHECK(worst < 1e-3 * diagonal);  // measured 5.5e-5
    CHECK(mean_distance(fitted) < 1e-3 * diagonal);
  }
}

TEST_CASE("batch transfer equals single calls, for any thread count", "[deformation_transfer]") {
  const Mesh source = test::bumpy_patch(16);
  const Mesh target = test::quad_grid(
      11, 14, 2.1, 1.9, [](double x, double y) { return 0.5 * std::exp(-((x - 1) * (x - 1) + (y - 1) * (y - 1))); });
  std::vector<LandmarkPair> landmarks;
  for (int j = 0; j <= 16; j += 4)
    for (int i = 0; i <= 16; i += 4) {
      const Eigen::RowVector3d p = source.vertices.row(j * 17 + i);
      int nearest = 0;
      (target.vertices.rowwise() - p).rowwise().squaredNorm().minCoeff(&nearest);
      landmarks.push_back({j * 17 + i, nearest});
    }
  std::vector<Positions> expressions{source.vertices, expression(source.vertices),
                                     transform(source.vertices, 1.1 * Eigen::Matrix3d::Identity(),
                                               Eigen::Vector3d(1, 1, 0), Eigen::Vector3d(0, 0, 0.2))};
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const DeformationTransfer one(source, target, landmarks);
  const std::vector<Positions> batch_one = one.transfer(expressions);
  omp_set_num_threads(2);
  const DeformationTransfer two(source, target, landmarks);
  const std::vector<Positions> batch_two = two.transfer(expressions);
  omp_set_num_threads(threads);

  CHECK(one.fitted_source() == two.fitted_source());
  CHECK(one.triangle_pairs() == two.triangle_pairs());
  REQUIRE(batch_one.size() == expressions.size());
  REQUIRE(batch_two.size() == expressions.size());
  for (size_t k = 0; k < expressions.size(); ++k) {
    CHECK(batch_one[k] == one.transfer(expressions[k]));
    CHECK(batch_one[k] == batch_two[k]);
    CHECK(batch_one[k].allFinite());
  }
  CHECK(deformation_transfer(source, expressions[1], target, landmarks) == batch_one[1]);
}

TEST_CASE("degenerate triangles and unmatched target parts stay finite", "[deformation_transfer]") {
  const Mesh base_source = test::bumpy_patch(12);
  const Mesh base_target = other_patch(12);
  // A zero-area triangle (a repeated corner) in each mesh.
  Triangles source_triangles(base_source.triangle_count() + 1, 3);
  source_triangles << base_source.triangles, Eigen::RowVector3i(0, 1, 1);
  const Mesh source = mesh_from_triangles(base_source.vertices, source_triangles);
  // The target also gets a far-away part facing down, which no source triangle matches.
  const Mesh flipped = test::quad_grid(2, 2, 0.5, 0.5, [](double, double) { return 0.0; });
  const int nv = base_target.vertex_count();
  Positions target_vertices(nv + flipped.vertex_count(), 3);
  target_vertices << base_target.vertices, flipped.vertices.rowwise() + Eigen::RowVector3d(10, 0, 3);
  Triangles target_triangles(base_target.triangle_count() + 1 + flipped.triangle_count(), 3);
  target_triangles << base_target.triangles, Eigen::RowVector3i(1, 2, 2),
      (flipped.triangles.rowwise().reverse().array() + nv).matrix();
  const Mesh target = mesh_from_triangles(target_vertices, target_triangles);
  std::vector<LandmarkPair> landmarks;
  for (int j = 0; j <= 12; j += 3)
    for (int i = 0; i <= 12; i += 3) landmarks.push_back({j * 13 + i, j * 13 + i});

  const DeformationTransfer dt(source, target, landmarks);
  const auto& report = dt.report();
  CHECK(report.degenerate_source_triangles == 1);
  CHECK(report.degenerate_target_triangles == 1);
  CHECK(report.identity_target_triangles == flipped.triangle_count());
  CHECK(report.target_components == 2);
  CHECK(dt.fitted_source().allFinite());
  const Positions result = dt.transfer(expression(source.vertices));
  REQUIRE(result.allFinite());
  // The unmatched part keeps its shape (held to the identity) and only moves.
  const Positions part = result.bottomRows(flipped.vertex_count());
  const Positions part_rest = target.vertices.bottomRows(flipped.vertex_count());
  const Positions offset = part - part_rest;
  CHECK((offset.rowwise() - offset.row(0)).cwiseAbs().maxCoeff() < 1e-9);
  // The rest of the target stays put for the undeformed source.
  CHECK((dt.transfer(source.vertices) - target.vertices).cwiseAbs().maxCoeff() < 1e-9);
}

TEST_CASE("bad input is reported with the landmark, the index and the mesh", "[deformation_transfer]") {
  Mesh source = test::bumpy_patch(8);
  source.source = "human.obj";
  Mesh target = other_patch(6);
  target.source = "avatar.obj";
  std::vector<LandmarkPair> landmarks{{0, 0}, {8, 6}, {80, 48}, {72, 42}};

  SECTION("source index out of range") {
    auto bad = landmarks;
    bad[2].source = 81;
    const std::string message = error_of([&] { DeformationTransfer(source, target, bad); });
    CHECK_THAT(message, Catch::Contains("landmark 2") && Catch::Contains("81") && Catch::Contains("human.obj") &&
                            Catch::Contains("81 vertices"));
  }
  SECTION("target index out of range") {
    auto bad = landmarks;
    bad[3].target = -1;
    const std::string message = error_of([&] { DeformationTransfer(source, target, bad); });
    CHECK_THAT(message, Catch::Contains("landmark 3") && Catch::Contains("-1") && Catch::Contains("avatar.obj") &&
                            Catch::Contains("49 vertices"));
  }
  SECTION("a source vertex used twice") {
    auto bad = landmarks;
    bad[3].source = 8;
    const std::string message = error_of([&] { DeformationTransfer(source, target, bad); });
    CHECK_THAT(message, Catch::Contains("landmark 3") && Catch::Contains("landmark 1"));
  }
  SECTION("fewer than 3 landmarks") {
    const std::vector<LandmarkPair> two(landmarks.begin(), landmarks.begin() + 2);
    const std::string message = error_of([&] { DeformationTransfer(source, target, two); });
    CHECK_THAT(message, Catch::Contains("at least 3") && Catch::Contains("got 2"));
  }
  SECTION("collinear landmarks cannot fix a rotation") {
    const Mesh flat = test::quad_grid(8, 8, 2.0, 2.0, [](double, double) { return 0.0; });
    const std::vector<LandmarkPair> line{{0, 0}, {4, 3}, {8, 6}};
    const std::string message = error_of([&] { DeformationTransfer(flat, target, line); });
    CHECK_THAT(message, Catch::Contains("one line"));
  }
  SECTION("an expression with the wrong vertex count") {
    const DeformationTransfer dt(source, target, landmarks);
    const Positions wrong = Positions::Zero(80, 3);
    const std::string message = error_of([&] { dt.transfer(wrong); });
    CHECK_THAT(message, Catch::Contains("80 vertices") && Catch::Contains("has 81"));
    const std::string batch = error_of([&] { dt.transfer(std::vector<Positions>{source.vertices, wrong}); });
    CHECK_THAT(batch, Catch::Contains("expression 1") && Catch::Contains("80 vertices"));
    const std::string one_off = error_of([&] { deformation_transfer(source, wrong, target, landmarks); });
    CHECK_THAT(one_off, Catch::Contains("80 vertices") && Catch::Contains("has 81"));
    Positions nan = source.vertices;
    nan(5, 1) = std::nan("");
    CHECK_THAT(error_of([&] { dt.transfer(nan); }), Catch::Contains("non-finite"));
  }
  SECTION("invalid options name the option") {
    struct Row {
      std::function<void(DeformationTransferOptions&)> spoil;
      std::string name;
    };
    const std::vector<Row> table{
        {[](auto& o) { o.smoothness_weight = -1; }, "deformation_transfer.smoothness_weight"},
        {[](auto& o) { o.identity_weight = 0; }, "deformation_transfer.identity_weight"},
        {[](auto& o) { o.closest_point_weights = {}; }, "deformation_transfer.closest_point_weights"},
        {[](auto& o) {
           o.closest_point_weights = {0, 1, NAN};
         },
         "deformation_transfer.closest_point_weights[2]"},
        {[](auto& o) { o.landmark_weight = -2; }, "deformation_transfer.landmark_weight"},
        {[](auto& o) { o.max_normal_angle_deg = 0; }, "deformation_transfer.max_normal_angle_deg"},
        {[](auto& o) { o.max_normal_angle_deg = 200; }, "deformation_transfer.max_normal_angle_deg"},
        {[](auto& o) { o.match_distance = -0.1; }, "deformation_transfer.match_distance"},
    };
    for (const Row& row : table) {
      DeformationTransferOptions options;
      row.spoil(options);
      CHECK_THAT(error_of([&] { options.validate(); }), Catch::StartsWith(row.name + ":"));
      CHECK_THAT(error_of([&] { DeformationTransfer(source, target, landmarks, options); }),
                 Catch::StartsWith(row.name + ":"));
    }
    CHECK(error_of([] { DeformationTransferOptions{}.validate(); }).empty());
  }
}
