#include "geometry/dr_features.h"

#include <Eigen/Geometry>
#include <catch2/catch.hpp>

#include "deformations.h"
#include "geometry/rotation.h"
#include "test_support.h"

using namespace retarget;

namespace {
Eigen::Matrix3d stretch_of(const float* f) {
  Eigen::Matrix3d S;
  S << f[3] + 1.0, f[4], f[5], f[4], f[6] + 1.0, f[7], f[5], f[7], f[8] + 1.0;
  return S;
}
}  // namespace

TEST_CASE("the rest pose gives all-zero features", "[dr_features]") {
  for (const Mesh& mesh : {test::bumpy_patch(12), test::uv_sphere(10, 14), test::tube(6, 10)}) {
    const DrFeatureMatrix f = DrFeatures(mesh).compute(mesh.vertices);
    CHECK(f.cwiseAbs().maxCoeff() < 1e-6f);
  }
}

TEST_CASE("a flat mesh at rest still gives zeros (the normal term fixes the out-of-plane direction)", "[dr_features]") {
  const Mesh flat = test::quad_grid(6, 5, 1.0, 1.0, [](double, double) { return 0.0; });
  CHECK(DrFeatures(flat).compute(flat.vertices).cwiseAbs().maxCoeff() < 1e-6f);
}

TEST_CASE("a rigid motion gives S = I and log R = the rotation vector everywhere", "[dr_features]") {
  const Mesh mesh = test::uv_sphere(12, 16);
  const Eigen::Vector3d axis = Eigen::Vector3d(1, -2, 0.5).normalized();
  for (double angle : {0.3, 2.5, M_PI - 1e-4}) {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    const DrFeatureMatrix f = DrFeatures(mesh).compute(test::rigid_motion(mesh.vertices, R, {4, 5, -6}));
    for (int v = 0; v < f.rows(); ++v) {
      INFO("angle " << angle << ", vertex " << v);
      const Eigen::Vector3d r(f(v, 0), f(v, 1), f(v, 2));
      CHECK((r - angle * axis).norm() < 1e-5);
      CHECK(f.row(v).tail<6>().cwiseAbs().maxCoeff() < 1e-5f);
    }
  }
}

TEST_CASE("a uniform scale s gives S = s I and no rotation", "[dr_features]") {
  const Mesh mesh = test::bumpy_patch(10);
  for (double s : {0.5, 1.7}) {
    const DrFeatureMatrix f = DrFeatures(mesh).compute(mesh.vertices * s);
    for (int v = 0; v < f.rows(); ++v) {
      INFO("scale " << s << ", vertex " << v);
      CHECK(f.row(v).head<3>().norm() < 1e-5f);
      CHECK((stretch_of(f.row(v).data()) - s * Eigen::Matrix3d::Identity()).norm() < 1e-5);
    }
  }
}

TEST_CASE("an affine map is recovered exactly by the one-ring fit", "[dr_features]") {
  const Mesh mesh = test::uv_sphere(10, 12);
  Eigen::Matrix3d A;
  A << 1.2, 0.1, 0.0, -0.2, 0.9, 0.3, 0.05, 0.0, 1.1;
  const DrFeatures features(mesh, DrOptions{EdgeWeighting::cotangent, false});
  const Positions deformed = mesh.vertices * A.transpose();
  for (int v = 0; v < mesh.vertex_count(); v += 7)
    CHECK((features.deformation_gradient(deformed, v) - A).norm() < 1e-9);
  const DrFeatureMatrix f = features.compute(deformed);
  for (int v = 0; v < mesh.vertex_count(); v += 7) CHECK((unpack_dr(f.row(v).data()) - A).norm() < 1e-5);
}

TEST_CASE("degenerate faces give finite features", "[dr_features]") {
  Mesh mesh = test::bumpy_patch(6);
  // Collapse one quad to a sliver, and add a zero-area face on top of an existing edge.
  mesh.vertices.row(8) = mesh.vertices.row(9);
  const int sliver[3] = {0, 1, 1};
  mesh.faces.add(sliver, 3);
  triangulate(mesh);
  const DrFeatures features(mesh);
  CHECK(features.compute(mesh.vertices).allFinite());
  CHECK(features.compute(test::bend(mesh.vertices, 40, 0.5, 1.5)).allFinite());
}

TEST_CASE("batched and threaded features equal one-by-one features exactly", "[dr_features]") {
  const Mesh mesh = test::tube(16, 20);
  std::vector<Positions> frames;
  for (int k = 0; k < 6; ++k) frames.push_back(test::twist(mesh.vertices, 25.0 * k, 0.2, 1.8));
  std::vector<const Positions*> pointers;
  for (const Positions& f : frames) pointers.push_back(&f);
  const size_t stride = static_cast<size_t>(mesh.vertex_count()) * kDrWidth;
  std::vector<std::vector<float>> results;
  for (int threads : {1, 2}) {
    DrOptions options;
    options.threads = threads;
    const DrFeatures features(mesh, options);
    std::vector<float> batch(frames.size() * stride);
    features.compute_batch(pointers, batch.data());
    for (size_t k = 0; k < frames.size(); ++k) {
      const DrFeatureMatrix single = features.compute(frames[k]);
      CHECK(std::equal(single.data(), single.data() + stride, batch.data() + k * stride));
    }
    results.push_back(batch);
  }
  CHECK(results[0] == results[1]);
}

TEST_CASE("bad options and a wrong vertex count are refused with a message", "[dr_features]") {
  const Mesh mesh = test::tube(4, 8);
  DrOptions bad;
  bad.threads = -1;
  CHECK_THROWS_WITH(DrFeatures(mesh, bad), Catch::Contains("dr.threads"));
  bad = DrOptions{};
  bad.normal_weight = 0;
  CHECK_THROWS_WITH(DrFeatures(mesh, bad), Catch::Contains("dr.normal_weight"));
  const Positions wrong = Positions::Zero(mesh.vertex_count() + 2, 3);
  CHECK_THROWS_WITH(DrFeatures(mesh).compute(wrong),
                    Catch::Contains("42 vertices") && Catch::Contains("rest mesh has 40"));
}
