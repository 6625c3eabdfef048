// The error of one output expression against its ground truth, where expressions happen: the
// output is rigidly aligned onto the truth (rotation + translation over every vertex), then
// per-vertex distances are averaged over every vertex, over the vertices the rig moves, and
// over each face region's vertices (geometry/rig_footprint.h). The trivial answer (the rest
// mesh) scored by the same function is what every method's figure is compared with.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "geometry/mesh.h"
#include "geometry/rig_footprint.h"

namespace retarget {

struct ExpressionError {
  double mean = 0;  // mean per-vertex distance over every vertex, times `scale` (mm)
  double max = 0;   // largest per-vertex distance
  int worst_vertex = -1;
  double moving_mean = 0;                     // over footprint.moving (= mean when it is empty)
  std::map<std::string, double> region_mean;  // over each of footprint.regions
};

// output, truth: #V x 3 in one unit; scale: mm per unit. Throws retarget::Error when the vertex
// counts differ.
ExpressionError expression_error(const Positions& output, const Positions& truth, double scale,
                                 const RigFootprint& footprint);

// Running sums of ExpressionError over many faces (means of the per-face means).
struct ExpressionErrorSum {
  int count = 0;
  double mean = 0, max = 0, mean_of_max = 0, moving_mean = 0;
  std::map<std::string, double> region_mean;
  void add(const ExpressionError& e);
  ExpressionErrorSum averaged() const;  // sums divided by count (max stays the largest)
};

}  // namespace retarget
