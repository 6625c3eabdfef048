// Landmarks proposed from the rig alone, checked against the synthetic avatars' own landmarks
// (the generator knows them) and against the rig turned, welded apart and stripped.
#include "avatar/landmark_proposals.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <utility>

#include "geometry/metrics.h"
#include "scratch.h"
#include "synthetic/avatar_trim.h"
#include "synthetic/synthetic_faces.h"

namespace retarget {
namespace landmark_proposals_test {

using Catch::Matchers::Contains;
using test::error_of;

// The landmarks the openings define: proposed for every avatar, held to 3% of the eye distance.
const std::vector<std::string> kOpeningLandmarks = {"mouth_left",         "mouth_right",       "lip_upper_center",
                                                    "lip_lower_center",   "eye_inner_left",    "eye_inner_right",
                                                    "eye_outer_left",     "eye_outer_right",   "eyelid_upper_left",
                                                    "eyelid_upper_right", "eyelid_lower_left", "eyelid_lower_right"};

Eigen::Vector3d centre(const Positions& V, const std::vector<int>& set) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int v : set) c += V.row(v).transpose();
  return c / static_cast<double>(set.size());
}

double true_eye_distance(const Rig& rig) {
  return (centre(rig.neutral.vertices, rig.eyes.left) - centre(rig.neutral.vertices, rig.eyes.right)).norm();
}

// The rig with every vertex moved by x -> scale * R x + t (offsets by scale * R).
Rig moved(const Rig& rig, const Eigen::Matrix3d& R, double scale, const Eigen::Vector3d& t) {
  Rig out = rig;
  out.neutral.vertices = ((scale * rig.neutral.vertices * R.transpose()).rowwise() + t.transpose()).eval();
  for (Controller& c : out.controllers) c.offset = (scale * c.offset * R.transpose()).eval();
  return out;
}

// The rig with every triangle given its own three vertices (a skin exported unwelded).
Rig unwelded(const Rig& rig) {
  Rig out = rig;
  const Triangles& T = rig.neutral.triangles;
  Positions V(3 * T.rows(), 3);
  Triangles F(T.rows(), 3);
  for (Eigen::Index t = 0; t < T.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      V.row(3 * t + k) = rig.neutral.vertices.row(T(t, k));
      F(t, k) = static_cast<int>(3 * t + k);
    }
  out.neutral = mesh_from_triangles(V, F, "unwelded");
  for (size_t c = 0; c < rig.controllers.size(); ++c) {
    Positions D(3 * T.rows(), 3);
    for (Eigen::Index t = 0; t < T.rows(); ++t)
      for (int k = 0; k < 3; ++k) D.row(3 * t + k) = rig.controllers[c].offset.row(T(t, k));
    out.controllers[c].offset = D;
  }
  out.landmarks.clear();
  out.eyes = {};
  return out;
}

TEST_CASE("landmarks proposed from the synthetic avatars' rigs lie within 3% of the eye distance of the true ones",
          "[avatar][landmarks]") {
  for (const SyntheticAvatar& avatar : synthetic_avatars()) {
    const Rig& rig = avatar.rig;
    INFO(rig.name);
    const LandmarkProposal proposal = propose_landmarks(rig);
    const double eye_distance = true_eye_distance(rig);
    for (const std::string& name : kOpeningLandmarks) {
      INFO(name);
      REQUIRE(proposal.landmarks.count(name) == 1);
      REQUIRE(rig.landmarks.count(name) == 1);
      const int proposed = proposal.landmarks.at(name).vertex, truth = rig.landmarks.at(name);
      CHECK((rig.neutral.vertices.row(proposed) - rig.neutral.vertices.row(truth)).norm() <= 0.03 * eye_distance);
      CHECK(proposal.landmarks.at(name).confidence > 0.5);
    }
    // Every name both have (brows, nose tip, chin too), within 3% of the eye distance. Except the
    // fox's brow inner ends (6.6% today, held there): its table puts them 0.3 cm further out than
    // its inner eye corners, where its brow raiser still lifts the brow by 54% of its peak; the
    // moppet's and glorp's tables put theirs where it lifts 26% and 18% (docs/usage/avatars.md).
    int shared = 0;
    for (const auto& [name, proposed] : proposal.landmarks) {
      const auto truth = rig.landmarks.find(name);
      if (truth == rig.landmarks.end()) continue;
      INFO(name);
      ++shared;
      const double distance =
          (rig.neutral.vertices.row(proposed.vertex) - rig.neutral.vertices.row(truth->second)).norm() / eye_distance;
      CHECK(distance <= (rig.name == "fox" && name.rfind("brow_inner_", 0) == 0 ? 0.07 : 0.03));
    }
    CHECK(shared >= 19);  // the twelve, the chin and six brow points (glorp has no nose tip)
    // The eyes give the paper's scale: the same mm per unit within 3%.
    CHECK(std::abs(millimetres_per_unit(rig.neutral.vertices, proposal.eyes) /
                       millimetres_per_unit(rig.neutral.vertices, rig.eyes) -
                   1) < 0.03);
    // The frame: the synthetic faces look along +z with +y up and +x their left.
    CHECK(proposal.frame.left.dot(Eigen::Vector3d::UnitX()) > 0.99);
    CHECK(proposal.frame.up.dot(Eigen::Vector3d::UnitY()) > 0.9);
    CHECK(proposal.frame.forward.dot(Eigen::Vector3d::UnitZ()) > 0.9);
    CHECK(proposal.mirror.error < 0.001);
  }
}

TEST_CASE("on a many-part head the landmarks hold and the eye parts are the eyeballs, not brows or irises",
          "[avatar][landmarks][parts]") {
  const SyntheticAvatar fox = synthetic_avatars()[1];
  const Rig bramble = with_many_parts(fox, "bramble").rig;  // lashes, brows, irises, teeth, two skin islands
  const LandmarkProposal proposal = propose_landmarks(bramble);
  const double eye_distance = true_eye_distance(bramble);
  for (const std::string& name : kOpeningLandmarks) {
    INFO(name);
    REQUIRE(proposal.landmarks.count(name) == 1);
    CHECK((bramble.neutral.vertices.row(proposal.landmarks.at(name).vertex) -
           bramble.neutral.vertices.row(bramble.landmarks.at(name)))
              .norm() <= 0.03 * eye_distance);
  }
  int eyes = 0;
  for (const ProposedPart& part : proposal.parts) {
    if (part.kind != ProposedPart::Kind::eye) continue;
    ++eyes;
    INFO(part.name << ": " << part.vertices.size() << " vertices from " << part.vertices.front());
    CHECK(part.vertices == bramble.parts[part.name == "eye_left" ? 0 : 1].vertices);
  }
  CHECK(eyes == 2);
}

TEST_CASE("the proposals follow the face, not the file's axes: a turned, scaled, moved rig gets the same vertices",
          "[avatar][landmarks]") {
  const Rig fox = synthetic_avatars()[1].rig;
  REQUIRE(fox.name == "fox");
  const LandmarkProposal upright = propose_landmarks(fox);
  // Z-up as Blender exports it, turned 30 degrees about the vertical, in metres, far from the origin.
  const Eigen::Matrix3d R =
      (Eigen::AngleAxisd(0.5236, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  const LandmarkProposal turned = propose_landmarks(moved(fox, R, 0.01, Eigen::Vector3d(3, -2, 1.5)));
  CHECK(turned.landmarks.size() == upright.landmarks.size());
  for (const auto& [name, landmark] : upright.landmarks) {  // the openings', the brows', nose tip and chin
    INFO(name);
    REQUIRE(turned.landmarks.count(name) == 1);
    CHECK(turned.landmarks.at(name).vertex == landmark.vertex);
  }
  CHECK((turned.frame.up - R * upright.frame.up).norm() < 0.01);
  CHECK((turned.frame.left - R * upright.frame.left).norm() < 0.01);
}

TEST_CASE("a skin of unwelded pieces is welded for the analysis only: the same places, the output's own indices",
          "[avatar][landmarks]") {
  const Rig moppet = synthetic_avatars()[0].rig;
  REQUIRE(moppet.name == "moppet");
  const LandmarkProposal whole = propose_landmarks(moppet);
  const Rig pieces = unwelded(moppet);
  const LandmarkProposal proposal = propose_landmarks(pieces);
  CHECK(proposal.welded > moppet.neutral.vertex_count());
  const double eye_distance = true_eye_distance(moppet);
  CHECK(proposal.landmarks.size() == whole.landmarks.size());
  for (const auto& [name, landmark] : whole.landmarks) {
    INFO(name);
    REQUIRE(proposal.landmarks.count(name) == 1);
    const int v = proposal.landmarks.at(name).vertex;
    REQUIRE(v < pieces.neutral.vertex_count());
    CHECK((pieces.neutral.vertices.row(v) - moppet.neutral.vertices.row(landmark.vertex)).norm() < 1e-9 * eye_distance);
  }
}

// The rig with every triangle split in four at its edges' midpoints (offsets likewise): the same
// surface and motion, four times the triangles; the old vertices keep their indices.
Rig split_in_four(const Rig& rig) {
  const Triangles& T = rig.neutral.triangles;
  std::map<std::pair<int, int>, int> middle;  // edge (low, high) -> new vertex
  std::vector<std::pair<int, int>> edges;
  const auto at = [&](int a, int b) {
    const std::pair<int, int> key{std::min(a, b), std::max(a, b)};
    const auto [it, added] = middle.emplace(key, rig.neutral.vertex_count() + static_cast<int>(edges.size()));
    if (added) edges.push_back(key);
    return it->second;
  };
  Triangles F(4 * T.rows(), 3);
  for (Eigen::Index t = 0; t < T.rows(); ++t) {
    const int a = T(t, 0), b = T(t, 1), c = T(t, 2);
    const int ab = at(a, b), bc = at(b, c), ca = at(c, a);
    F.row(4 * t) << a, ab, ca;
    F.row(4 * t + 1) << ab, b, bc;
    F.row(4 * t + 2) << ca, bc, c;
    F.row(4 * t + 3) << ab, bc, ca;
  }
  const auto refined = [&](const Positions& P) {
    Positions out(P.rows() + static_cast<Eigen::Index>(edges.size()), 3);
    out.topRows(P.rows()) = P;
    for (size_t e = 0; e < edges.size(); ++e)
      out.row(P.rows() + static_cast<Eigen::Index>(e)) = 0.5 * (P.row(edges[e].first) + P.row(edges[e].second));
    return out;
  };
  Rig out = rig;
  out.neutral = mesh_from_triangles(refined(rig.neutral.vertices), F, "split in four");
  for (Controller& c : out.controllers) c.offset = refined(c.offset);
  out.landmarks.clear();
  out.eyes = {};
  return out;
}

TEST_CASE("a finer mesh of the same face gets the same places: the proposals do not depend on the vertex density",
          "[avatar][landmarks]") {
  // Each synthetic avatar with four times its triangles; the generator's landmarks keep their
  // indices. Measured: every shared name within 3% of the eye distance except brow ends (moppet's
  // outer 3.3%, fox's outer 0-3.7% and inner 8.2%): they are read where the brow controllers lift
  // a quarter of their peak, and a finer mesh has vertices nearer that line.
  for (const SyntheticAvatar& avatar : synthetic_avatars()) {
    const Rig& rig = avatar.rig;
    INFO(rig.name);
    const Rig fine = split_in_four(rig);
    REQUIRE(fine.neutral.triangle_count() == 4 * rig.neutral.triangle_count());
    const LandmarkProposal proposal = propose_landmarks(fine);
    const double eye_distance = true_eye_distance(rig);
    int shared = 0;
    for (const auto& [name, truth] : rig.landmarks) {
      const auto it = proposal.landmarks.find(name);
      if (it == proposal.landmarks.end()) continue;
      ++shared;
      const double distance = (fine.neutral.vertices.row(it->second.vertex) - rig.neutral.vertices.row(truth)).norm();
      INFO(fmt::format("{}: {:.1f}% of the eye distance", name, 100 * distance / eye_distance));
      const bool brow_end = name.rfind("brow_inner_", 0) == 0 || name.rfind("brow_outer_", 0) == 0;
      CHECK(distance <= (brow_end ? 0.1 : 0.03) * eye_distance);
    }
    CHECK(shared >= 19);
    // The eyes are the same openings: the same centres, so the same millimetre scale.
    CHECK((centre(fine.neutral.vertices, proposal.eyes.left) - centre(rig.neutral.vertices, rig.eyes.left)).norm() <=
          0.03 * eye_distance);
    CHECK((centre(fine.neutral.vertices, proposal.eyes.right) - centre(rig.neutral.vertices, rig.eyes.right)).norm() <=
          0.03 * eye_distance);
  }
}

TEST_CASE("a placeholder morph that moves nothing is named, and the others still give every landmark",
          "[avatar][landmarks]") {
  const Rig fox = synthetic_avatars()[1].rig;
  const LandmarkProposal whole = propose_landmarks(fox);
  Rig rig = fox;
  const int twitch = rig.controller_index("snoutTwitch");
  REQUIRE(twitch >= 0);
  rig.controllers[static_cast<size_t>(twitch)].offset.setZero();
  CHECK(rig.still_controllers() == std::vector<std::string>{"snoutTwitch"});
  const LandmarkProposal proposal = propose_landmarks(rig);
  std::string notes;
  for (const std::string& note : proposal.notes) notes += note + "\n";
  CHECK_THAT(notes, Contains("1 of 22 controllers move no vertex") && Contains("snoutTwitch"));
  CHECK(proposal.landmarks.size() == whole.landmarks.size());
  for (const auto& [name, landmark] : whole.landmarks) {
    INFO(name);
    REQUIRE(proposal.landmarks.count(name) == 1);
    CHECK(proposal.landmarks.at(name).vertex == landmark.vertex);
  }
  for (const std::string& note : whole.notes) CHECK_THAT(note, !Contains("move no vertex"));
}

TEST_CASE("rigs that cannot show a face get a message saying what is missing and how to supply it",
          "[avatar][landmarks]") {
  const Rig fox = synthetic_avatars()[1].rig;
  SECTION("no controllers") {
    Rig rig = fox;
    rig.controllers.clear();
    const std::string message = error_of([&] { propose_landmarks(rig); });
    CHECK_THAT(message, Contains("no controllers") && Contains("landmarks:"));
  }
  SECTION("only a jaw: no eyes") {
    Rig rig = fox;
    const int jaw = rig.controller_index("jawOpen");
    REQUIRE(jaw >= 0);
    rig.controllers = {rig.controllers[static_cast<size_t>(jaw)]};
    CHECK_THAT(error_of([&] { propose_landmarks(rig); }), Contains("no eyes found"));
  }
  SECTION("only blinks: no mouth") {
    Rig rig = fox;
    rig.controllers = {rig.controllers[static_cast<size_t>(rig.controller_index("blinkLeft"))],
                       rig.controllers[static_cast<size_t>(rig.controller_index("blinkRight"))]};
    CHECK_THAT(error_of([&] { propose_landmarks(rig); }), Contains("no mouth found"));
  }
  SECTION("a single controller that moves nothing") {
    Rig rig = fox;
    rig.controllers.resize(1);
    rig.controllers[0].offset.setZero();
    CHECK_THAT(error_of([&] { propose_landmarks(rig); }), Contains("no eyes found"));
  }
  SECTION("a single triangle, two disconnected triangles: too few vertices, named with the file") {
    Positions one(3, 3);
    one << 0, 0, 0, 1, 0, 0, 0, 1, 0;
    Rig rig;
    rig.source = "tiny/rig.yaml";
    rig.neutral = mesh_from_triangles(one, (Triangles(1, 3) << 0, 1, 2).finished(), "tiny/neutral.obj");
    rig.controllers.push_back({"jawOpen", Positions::Constant(3, 3, 0.1), 0, 1});
    CHECK_THAT(error_of([&] { propose_landmarks(rig); }),
               Contains("tiny/rig.yaml") && Contains("the neutral mesh has 3 vertices and 1 triangles: too few"));
    Positions two(6, 3);
    two << 0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 0, 0, 6, 0, 0, 5, 1, 0;
    rig.neutral = mesh_from_triangles(two, (Triangles(2, 3) << 0, 1, 2, 3, 4, 5).finished(), "tiny/neutral.obj");
    rig.controllers[0].offset = Positions::Constant(6, 3, 0.1);
    CHECK_THAT(error_of([&] { propose_landmarks(rig); }),
               Contains("tiny/rig.yaml") && Contains("has 3 vertices: too few to be a face"));
  }
  SECTION("a lopsided head") {
    Rig rig = fox;
    Positions& V = rig.neutral.vertices;
    for (Eigen::Index v = 0; v < V.rows(); ++v)
      if (V(v, 0) > 0) V(v, 2) += 0.8 * V(v, 0) + 0.5 * std::sin(V(v, 1));
    CHECK_THAT(error_of([&] { propose_landmarks(rig); }), Contains("not mirror-symmetric"));
  }
}

}  // namespace landmark_proposals_test
}  // namespace retarget
