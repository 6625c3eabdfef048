// The many-part avatar (synthetic/avatar_trim.h): its pieces, its named parts, the skin's seam,
// and pieces that move with what they hang from.
#include "synthetic/avatar_trim.h"

#include <catch2/catch.hpp>

#include "geometry/mesh_topology.h"
#include "geometry/part_motion.h"
#include "scratch.h"

namespace retarget {
namespace avatar_trim_test {

using Catch::Matchers::Contains;

// The fox, as synthetic_set() dresses it.
const SyntheticAvatar& fox() {
  static const SyntheticAvatar m = synthetic_avatars()[1];
  return m;
}
const SyntheticAvatar& bramble() {
  static const SyntheticAvatar b = with_many_parts(fox(), "bramble");
  return b;
}

int piece_count(const Rig& rig) {
  return connected_components(edge_topology(rig.neutral.triangles), rig.neutral.vertex_count()).count();
}

TEST_CASE("many parts: lashes, brows, irises, two rows of teeth, a tongue, and the skin in two islands",
          "[synthetic][parts]") {
  const Rig& m = fox().rig;
  const Rig& b = bramble().rig;
  CHECK(b.name == "bramble");
  // The fox's own pieces (skin, two eyeballs, the mouth pocket, two ears) + 1 island + 4 lashes + 2
  // brows + 2 irises + 2 rows of teeth + a tongue.
  CHECK(piece_count(b) == piece_count(m) + 12);
  REQUIRE(b.parts.size() == 4);
  CHECK(b.parts[2].kind == PartKind::teeth);
  // One named part, two pieces: rig_parts_to_move moves each row on its own, and every unnamed
  // piece (lashes, brows, irises, the pocket, the skin's second island) too.
  CHECK(rig_parts_to_move(b).size() == static_cast<size_t>(piece_count(b) - 1));
  // The base's vertices keep their indices: landmarks and eye sets still mean the same.
  CHECK(b.landmarks == m.landmarks);
  CHECK(b.eyes.left == m.eyes.left);
  for (const Controller& c : b.controllers) REQUIRE(c.offset.rows() == b.neutral.vertex_count());
  CHECK(b.neutral.vertices.topRows(m.neutral.vertex_count()) == m.neutral.vertices);
}

TEST_CASE("many parts: the seam's twins coincide and move alike; the lower teeth go with the jaw, the upper stay",
          "[synthetic][parts]") {
  const Rig& m = fox().rig;
  const Rig& b = bramble().rig;
  const int n = m.neutral.vertex_count();
  // The twins are appended first: each coincides with one base vertex and shares its offsets.
  int twins = 0;
  for (int v = n; v < b.neutral.vertex_count(); ++v) {
    int same = -1;
    for (int u = 0; u < n && same < 0; ++u)
      if (b.neutral.vertices.row(u) == b.neutral.vertices.row(v)) same = u;
    if (same < 0) break;
    ++twins;
    for (const Controller& c : b.controllers) REQUIRE(c.offset.row(v) == c.offset.row(same));
  }
  CHECK(twins > 20);
  // The pieces' own vertices are all distinct: no zero-length edge for the features to divide by.
  for (int v = n + twins; v < b.neutral.vertex_count(); ++v)
    for (int u = v + 1; u < b.neutral.vertex_count(); ++u)
      REQUIRE((b.neutral.vertices.row(u) - b.neutral.vertices.row(v)).norm() > 1e-4);
  const Controller& jaw = b.controllers[static_cast<size_t>(b.controller_index("jawOpen"))];
  const std::vector<int>& teeth = b.parts[2].vertices;
  const int row = static_cast<int>(teeth.size()) / 2;
  const double upper = jaw.offset.row(teeth.front()).norm(), lower = jaw.offset.row(teeth.back()).norm();
  INFO("upper teeth move " << upper << " cm, lower " << lower << " cm at jawOpen 1");
  CHECK(lower > 0.3);
  CHECK(upper == 0);
  CHECK(jaw.offset.row(teeth[static_cast<size_t>(row)]) == jaw.offset.row(teeth.back()));  // rigid: one offset
  // On the skull and the jaw: no other controller moves the teeth (a smile moves the lips only).
  for (const Controller& c : b.controllers)
    if (&c != &jaw)
      for (int v : teeth) REQUIRE(c.offset.row(v).norm() == 0);
}

TEST_CASE("many parts: a base without what the pieces hang from is refused", "[synthetic][parts]") {
  SyntheticAvatar bare = fox();
  bare.rig.landmarks.erase("brow_middle_left");
  CHECK_THAT(test::error_of([&] { with_many_parts(bare, "x"); }), Contains("brow_middle_left"));
  bare = fox();
  bare.rig.eyes = {};
  CHECK_THAT(test::error_of([&] { with_many_parts(bare, "x"); }), Contains("eye sets"));
}

}  // namespace avatar_trim_test
}  // namespace retarget
