#include "geometry/reconstruction.h"

#include <Eigen/Geometry>
#include <catch2/catch.hpp>

#include "deformations.h"
#include "geometry/dr_features.h"
#include "geometry/metrics.h"
#include "geometry/rigid_alignment.h"
#include "test_support.h"

using namespace retarget;

namespace {

// Round trip features(M) -> reconstruct, compared with M after the best rigid alignment;
// returns the error relative to the bounding-box diagonal.
VertexError round_trip(const Mesh& rest, const Positions& deformed,
                       EdgeWeighting weighting = EdgeWeighting::cotangent) {
  DrOptions dr;
  dr.weighting = weighting;
  ReconstructionOptions ro;
  ro.weighting = weighting;
  const DrFeatures features(rest, dr);
  const Reconstruction reconstruction(rest, ro);
  const Positions result = reconstruction.reconstruct(features.compute(deformed));
  const Positions aligned = rigid_alignment(result, deformed).apply(result);
  return vertex_error(aligned, deformed, 1.0 / bounding_box_diagonal(deformed));
}

}  // namespace

TEST_CASE("the rest pose reconstructs itself exactly", "[reconstruction]") {
  const Mesh rest = test::bumpy_patch(20);
  const DrFeatures features(rest);
  const Reconstruction reconstruction(rest);
  const Positions result = reconstruction.reconstruct(features.compute(rest.vertices));
  // No alignment: the pinned vertex and the centroid convention put it back in place.
  CHECK(vertex_error(result, rest.vertices).max < 1e-6);
}

TEST_CASE("round trip on smooth deformations stays within 3e-4 of the diagonal", "[reconstruction]") {
  struct Case {
    const char* name;
    Mesh rest;
    Positions deformed;
  };
  const Mesh tube = test::tube(60, 48, 0.5, 2.0);
  const Mesh patch = test::bumpy_patch(48);
  const Mesh sphere = test::uv_sphere(40, 64);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  std::vector<Case> cases = {
      {"twist 90", tube, test::twist(tube.vertices, 90, 0.5, 1.8)},
      {"twist 170", tube, test::twist(tube.vertices, 170, 0.4, 1.9)},
      {"bend 60", patch, test::bend(patch.vertices, 60, 0.8, 1.8)},
      {"bulge", sphere, test::bulge(sphere.vertices, {0, 0, 1}, 0.5, {0, 0.3, 1}, 0.35)},
      {"bulge + rigid", sphere,
       test::rigid_motion(test::bulge(sphere.vertices, {1, 0, 0}, 0.6, {1, 0, 0}, -0.3), R, {3, -1, 2})},
  };
  for (const Case& c : cases) {
    for (EdgeWeighting weighting : {EdgeWeighting::cotangent, EdgeWeighting::uniform}) {
      const VertexError e = round_trip(c.rest, c.deformed, weighting);
      INFO(c.name << " (" << to_string(weighting) << "): mean " << e.mean << ", max " << e.max);
      CHECK(e.mean <= 3e-4);
      CHECK(e.max <= 3e-3);
    }
  }
}

TEST_CASE("translation is fixed: each part keeps its rest centroid unless aligned", "[reconstruction]") {
  // Two disjoint parts (two spheres); each needs its own pinned vertex.
  Mesh a = test::uv_sphere(12, 16);
  Mesh b = test::uv_sphere(12, 16);
  Mesh both;
  both.vertices.resize(a.vertex_count() * 2, 3);
  both.vertices << a.vertices, (b.vertices.rowwise() + Eigen::RowVector3d(5, 0, 0));
  both.faces = a.faces;
  for (int f = 0; f < b.faces.size(); ++f) {
    std::vector<int> face(b.faces.begin(f), b.faces.begin(f) + b.faces.degree(f));
    for (int& v : face) v += a.vertex_count();
    both.faces.add(face.data(), static_cast<int>(face.size()));
  }
  triangulate(both);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Positions moved = test::rigid_motion(both.vertices, R, {1, 2, 3});
  const DrFeatures features(both);
  const Positions result = Reconstruction(both).reconstruct(features.compute(moved));
  // Rotated back into the rest frame, each part is exactly its rest part.
  CHECK(vertex_error(result, both.vertices).max > 0.1);  // the rotation is kept...
  const Eigen::RowVector3d c0 = result.topRows(a.vertex_count()).colwise().mean();
  const Eigen::RowVector3d c1 = result.bottomRows(a.vertex_count()).colwise().mean();
  CHECK((c0 - a.vertices.colwise().mean()).norm() < 1e-9);  // ...but not the translation
  CHECK((c1 - (a.vertices.colwise().mean() + Eigen::RowVector3d(5, 0, 0))).norm() < 1e-9);
}

TEST_CASE("align_to_rest undoes a rigid motion", "[reconstruction]") {
  const Mesh rest = test::uv_sphere(12, 16);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Positions moved = test::rigid_motion(rest.vertices, R, {1, 2, 3});
  ReconstructionOptions aligned;
  aligned.align_to_rest = true;
  const Positions back = Reconstruction(rest, aligned).reconstruct(DrFeatures(rest).compute(moved));
  CHECK(vertex_error(back, rest.vertices).max < 1e-6);
}

TEST_CASE("batch reconstruction equals single frames for 1 and 2 threads", "[reconstruction]") {
  const Mesh rest = test::tube(20, 24);
  const DrFeatures features(rest);
  std::vector<Positions> frames;
  for (int k = 0; k < 5; ++k) frames.push_back(test::twist(rest.vertices, 30.0 * k, 0.5, 1.5));
  std::vector<const Positions*> pointers;
  for (const Positions& f : frames) pointers.push_back(&f);
  std::vector<float> batch(frames.size() * rest.vertex_count() * kDrWidth);
  features.compute_batch(pointers, batch.data());
  for (int threads : {1, 2}) {
    ReconstructionOptions options;
    options.threads = threads;
    const Reconstruction reconstruction(rest, options);
    const std::vector<Positions> result =
        reconstruction.reconstruct_batch(batch.data(), static_cast<int>(frames.size()));
    for (size_t k = 0; k < frames.size(); ++k)
      CHECK(result[k] == reconstruction.reconstruct(batch.data() + k * rest.vertex_count() * kDrWidth));
  }
}

TEST_CASE("features with the wrong number of rows are refused", "[reconstruction]") {
  const Mesh rest = test::tube(4, 8);
  const DrFeatureMatrix wrong = DrFeatureMatrix::Zero(rest.vertex_count() - 1, kDrWidth);
  CHECK_THROWS_WITH(Reconstruction(rest).reconstruct(wrong),
                    Catch::Contains("features have 39 rows") && Catch::Contains("40 vertices"));
}

TEST_CASE("anchors hold the still region and stop drift from feature errors elsewhere", "[reconstruction]") {
  // A sphere whose cap around +z bulges; everything below z = 0.3 never moves.
  const Mesh sphere = test::uv_sphere(40, 64);
  Positions deformed = sphere.vertices;
  for (int v = 0; v < sphere.vertex_count(); ++v) {
    const double z = sphere.vertices(v, 2);
    if (z > 0.3) deformed.row(v) += 0.8 * (z - 0.3) * (z - 0.3) * sphere.vertices.row(v);  // a smooth swelling
  }
  std::vector<int> still;
  for (int v = 0; v < sphere.vertex_count(); ++v)
    if ((deformed.row(v) - sphere.vertices.row(v)).norm() == 0) still.push_back(v);
  REQUIRE(static_cast<Eigen::Index>(still.size()) > sphere.vertices.rows() / 2);
  const DrFeatures dr(sphere);
  Eigen::Matrix<float, Eigen::Dynamic, 9, Eigen::RowMajor> features = dr.compute(deformed);
  // Feature errors where the expression happens (as a decoder makes them): a stretch of 5%.
  for (int v = 0; v < sphere.vertex_count(); ++v)
    if (sphere.vertices(v, 2) > 0.6) features(v, 3) += 0.05f;

  ReconstructionOptions anchored_options;
  anchored_options.anchors = still;
  const Reconstruction free(sphere), anchored(sphere, anchored_options);
  const Positions a = anchored.reconstruct(features), f = free.reconstruct(features);
  double anchored_still = 0, free_still = 0;
  for (int v : still) {
    anchored_still = std::max(anchored_still, (a.row(v) - deformed.row(v)).norm());
    free_still = std::max(free_still, (rigid_alignment(f, deformed).apply(f).row(v) - deformed.row(v)).norm());
  }
  CHECK(anchored_still < 1e-12);  // exactly at rest
  CHECK(free_still > 1e-3);       // the free part carries the error over the whole sphere
  // Overall the anchored answer is nearer, even after the free one is aligned as well as can be.
  const Positions f_aligned = rigid_alignment(f, deformed).apply(f);
  CHECK(vertex_error(a, deformed).mean < vertex_error(f_aligned, deformed).mean);

  // With exact features the anchored reconstruction is the deformed mesh itself.
  const Positions exact = anchored.reconstruct(dr.compute(deformed));
  CHECK(vertex_error(exact, deformed).max < 2e-3);
}

TEST_CASE("anchors out of range or listed twice are refused", "[reconstruction]") {
  const Mesh patch = test::bumpy_patch(6);
  ReconstructionOptions o;
  o.anchors = {0, patch.vertex_count()};
  CHECK_THROWS_WITH(Reconstruction(patch, o),
                    Catch::Contains("reconstruction.anchors") && Catch::Contains("out of range"));
  o.anchors = {3, 3};
  CHECK_THROWS_WITH(Reconstruction(patch, o), Catch::Contains("listed twice"));
}
