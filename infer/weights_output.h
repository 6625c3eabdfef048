// The avatar's controller weights for each retargeted frame (retarget-infer --weights): what an
// engine animates the avatar with, since it moves the avatar through its morph targets, not
// through mesh files.
//
// Each frame's weights are the bounded least-squares fit of the bundle's rig to the retargeted
// mesh as written (in the avatar rest's frame: aligned to the rest pose, or anchored), with a
// ridge towards the neutral against implausible combinations and, for sequences, a smoothness
// term towards the previous frame (geometry/rig_weight_fit.h; both scale-free). Frames must come
// in input order for that. The residual is the mean distance, over the vertices the rig moves,
// between the mesh and the rig at the solved weights: how much of the output the rig cannot make,
// in mm (the bundle's millimetres_per_unit) or, without a scale, in the avatar's own units.
//
// Files in the output folder, appended as frames complete under temporary names and renamed into
// place by finish() (core/atomic_file.h), so a reader never sees half of one:
//   weights.csv     frame,<controller names...>,residual_mm   one row per frame (RFC 4180 quoting)
//   weights.jsonl   {"frame": "...", "weights": {"<name>": w, ...}, "residual_mm": r}  per line
#pragma once

#include <Eigen/Core>
#include <fstream>
#include <string>
#include <vector>

#include "geometry/rig.h"
#include "geometry/rig_weight_fit.h"

namespace retarget {

struct WeightsOutputOptions {
  // Towards the neutral (RigWeightFitOptions::ridge, times the mean squared offset norm): keeps
  // near-collinear controllers from cancelling each other at large weights. Being relative to the
  // mean controller, it weighs more on controllers that move little (blinks beside a jaw), so it
  // biases them first: on the synthetic avatars' own expressions with every controller active the
  // fit's mean absolute weight error is 0.003-0.06 at 1e-4 and 0.03-0.15 at 1e-3; through the
  // runtime, 1e-4 was as good as 0 or better (docs/usage/inference.md, "Controller weights out").
  double ridge = 1e-4;
  // Towards the previous frame's weights (RigWeightFitOptions::smoothness), against frame-to-frame
  // jitter in sequences; 0: every frame on its own (single files, shuffled inputs).
  double smoothness = 0;
  bool csv = true;    // write weights.csv
  bool jsonl = true;  // write weights.jsonl
  // Throws retarget::Error naming --weights-ridge, --weights-smoothness or --weights-format.
  void validate() const;
};

// The unit residuals are reported in: mm when the bundle knows the rig's scale
// (millimetres_per_unit > 0), else the rig's own units ("mesh units" when it names none).
struct ResidualUnit {
  double scale = 1;  // residual units per rig unit
  std::string name;  // "mm", the rig's units or "mesh units"
};
ResidualUnit residual_unit(const Rig& rig, double millimetres_per_unit);

struct FrameWeights {
  Eigen::VectorXd weights;  // #controllers, each within its controller's range
  double residual = 0;      // mean distance over the rig's moving vertices: mm, or mesh units without a scale
};

class WeightsOutput {
 public:
  static constexpr const char* kCsvFile = "weights.csv";
  static constexpr const char* kJsonlFile = "weights.jsonl";

  // rig: the bundle's (LoadedBundle::rig), kept by reference: it must outlive this. The Gram
  // matrix is computed here, once. millimetres_per_unit: of the rig's units, 0 = unknown. Opens
  // the temporaries in `folder` (which must exist); throws retarget::Error naming a file that
  // cannot be opened, or a bad option.
  WeightsOutput(const Rig& rig, double millimetres_per_unit, const std::string& folder,
                const WeightsOutputOptions& options = {});
  ~WeightsOutput();  // an output not finished is discarded (its temporaries removed)
  WeightsOutput(const WeightsOutput&) = delete;
  WeightsOutput& operator=(const WeightsOutput&) = delete;

  // Solves the next frame (avatar: #Va x 3, the rig's units and frame) with the previous frame's
  // weights for the smoothness term, and appends its row and line. frame: its name (the input's
  // stem). Throws retarget::Error for a vertex count other than the rig's or a failed write.
  FrameWeights add(const std::string& frame, const Positions& avatar);

  // Renames the files into place. Throws retarget::Error naming a file that cannot be written.
  void finish();

  const std::vector<std::string>& files() const { return files_; }  // final paths, csv first
  int frames() const { return frames_; }
  double residual_mean() const { return frames_ > 0 ? residual_sum_ / frames_ : 0; }
  double residual_max() const { return residual_max_; }
  // "mm", or the rig's units ("mesh units" when it names none) when there is no scale.
  const std::string& residual_unit() const { return residual_unit_; }

 private:
  struct File {
    std::string path, temporary;
    std::ofstream out;
  };
  void open(File& file, const std::string& path);
  void check(File& file) const;

  const Rig& rig_;
  RigWeightFit fit_;
  double scale_ = 1;  // residual units per rig unit
  std::string residual_unit_;
  bool csv_ = false, jsonl_ = false, finished_ = false;
  File csv_file_, jsonl_file_;
  std::vector<std::string> files_;
  Eigen::VectorXd previous_;  // empty before the first frame
  int frames_ = 0;
  double residual_sum_ = 0, residual_max_ = 0;
};

}  // namespace retarget
