// The geometry demo on procedural face-like meshes: what `retarget demo` runs.
#pragma once

#include <string>
#include <vector>

namespace retarget {

struct GeometryDemoOptions {
  std::string out = "out/demo";  // output folder
  int source_resolution = 80;    // quads per side of the source face
  int target_columns = 47;       // the target has its own topology: columns x rows quads
  int target_rows = 61;
  void validate() const;
};

struct GeometryDemoRow {
  std::string expression;
  double roundtrip_mean_mm = 0, roundtrip_max_mm = 0;  // DR features -> reconstruction, source face
  double transfer_mean_mm = 0, transfer_max_mm = 0;    // deformation transfer vs. ground truth, target
  double features_ms = 0, reconstruction_ms = 0, transfer_ms = 0;
};

// Builds a source and a target face (different topology and proportions, eye distance
// 6.2 cm), a few analytic expressions defined on both, and runs the round trip and the
// deformation transfer; writes every mesh as OBJ under options.out and returns one row
// per expression (errors in mm under the paper's eye-distance convention).
std::vector<GeometryDemoRow> run_geometry_demo(const GeometryDemoOptions& options);

}  // namespace retarget
