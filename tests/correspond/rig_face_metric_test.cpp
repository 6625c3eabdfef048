#include "correspond/rig_face_metric.h"

#include <catch2/catch.hpp>

#include "test_support.h"

using namespace retarget;

namespace {

// Three controllers on disjoint vertices of a 5 x 5 grid, each moving its vertices by 1 along z:
// a mouth controller moving 4 vertices, an eye controller moving 1, and "ears" moving 9.
Rig three_part_rig() {
  Rig rig;
  rig.name = "parts";
  rig.source = "parts.yaml";
  rig.neutral = quad_grid(4, 4, 1.0, 1.0);
  const std::vector<std::vector<int>> moved = {{0, 1, 2, 3}, {12}, {15, 16, 17, 18, 19, 20, 21, 22, 23}};
  const char* names[] = {"smile", "blink", "ears"};
  for (size_t k = 0; k < moved.size(); ++k) {
    Controller c;
    c.name = names[k];
    c.offset = Positions::Zero(rig.neutral.vertex_count(), 3);
    for (const int v : moved[k]) c.offset(v, 2) = 1.0;
    rig.controllers.push_back(c);
  }
  return rig;
}

}  // namespace

TEST_CASE("the face metric compares faces part by part, over the parts a human face has", "[belief]") {
  const Rig rig = three_part_rig();
  const Dataset avatar;  // no eyes: the still threshold is 0.1 rig units
  // Every moving vertex: the ears, moving the most vertices, weigh the most.
  const Eigen::MatrixXd all = rig_face_metric(rig, avatar);
  CHECK(all(2, 2) > all(0, 0));
  CHECK(all(0, 0) > all(1, 1));
  // As the prior reads the rig: smile is a mouth shape, blink an eye shape, the ears nothing
  // human. The ears are not compared, and each region counts once however many vertices it has.
  const Eigen::MatrixXd parts =
      rig_face_metric(rig, avatar, {{"smile", {"mouthSmile_L"}}, {"blink", {"eyeBlink_L"}}, {"ears", {}}});
  CHECK(parts(2, 2) == Approx(0).margin(1e-12));
  CHECK(parts(0, 0) == Approx(parts(1, 1)));
  CHECK(parts(0, 1) == Approx(0).margin(1e-12));
  CHECK(parts.diagonal().mean() == Approx(1));
  // A table that names no human part at all falls back to every moving vertex.
  CHECK(rig_face_metric(rig, avatar, {{"smile", {}}, {"blink", {}}, {"ears", {}}}).isApprox(all));
}
