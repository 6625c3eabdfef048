// Welding a rig's vertices for the maths, never for the output: vertices that sit at the same
// place at rest AND move identically under every controller are one point of the surface
// (texture-seam duplicates, a skin exported as unwelded pieces). Vertices that coincide at rest
// but part under some controller (lips stored as a seam, lids cut open) stay apart: the rig is
// the witness of what is one surface.
#pragma once

#include <vector>

#include "geometry/mesh.h"
#include "geometry/rig.h"

namespace retarget {

struct WeldOptions {
  // Coincidence at rest: within relative_tolerance x the neutral's bounding-box diagonal.
  double relative_tolerance = 1e-6;
  // Same motion: every controller's offsets differ by at most motion_tolerance x the largest
  // offset length of the whole rig (or of the rest tolerance, if larger).
  double motion_tolerance = 1e-4;

  // Throws retarget::Error naming `key_path`.<field> for a value that is not finite and > 0.
  void validate(const std::string& key_path = "weld") const;
};

struct Weld {
  std::vector<int> representative;  // #V: the lowest vertex index of each vertex's welded group
  Triangles triangles;              // #T' x 3 triangles over representatives, collapsed ones dropped
  int merged = 0;                   // vertices that are not their own representative
};

// The welded view of `rig` (its neutral's triangles and every controller's offsets).
Weld weld_rig_vertices(const Rig& rig, const WeldOptions& options = {});

}  // namespace retarget
