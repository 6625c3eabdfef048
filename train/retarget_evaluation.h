// The end-to-end check on faces with ground truth: human test meshes (train/test_faces.h) carried
// onto the avatar by several methods (retarget-infer outputs of full and stage-1 bundles, and
// deformation transfer alone, computed here), each compared with the avatar expression the
// controller table says is right: the recipe's blendshape weights mapped to controller weights
// (geometry/controller_correspondence.h) and evaluated on the rig.
//
// Errors: per-vertex distance in mm (avatar scaled so its eye centres are 10 cm apart) after a
// rigid alignment of each output onto its ground truth; and in rig-weight space, the controller
// weights fitted to the output as written (box-constrained least squares on the rig's offsets;
// retarget-infer aligns its outputs to the rest pose, deformation transfer keeps the rest's
// frame) against the ground-truth weights, mean absolute difference over all controllers.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace retarget {

struct RetargetEvaluationOptions {
  std::string faces;            // folder written by write_test_faces (faces.yaml + meshes)
  std::string correspondences;  // the correspondence folder: both datasets, the DT landmarks
  // name -> folder of avatar meshes <stem>.obj (or .ply), one per face (retarget-infer's output).
  std::vector<std::pair<std::string, std::string>> methods;
  bool deformation_transfer = true;  // add the method "dt": deformation transfer alone
  // Controller table; empty: correspondence.yaml beside the avatar rig's rig.yaml.
  std::string table;
  std::string out;     // metrics.json, contact_sheet.png and dt/ (the DT meshes) go here
  int sheet_rows = 8;  // faces on the contact sheet (distinct expressions first), >= 1
  int render_size = 256;  // pixels per picture on the sheet
  void validate() const;  // throws retarget::Error naming the option
};

struct MethodScore {
  std::string name;
  int samples = 0;
  double mean_mm = 0;         // mean over faces of the mean per-vertex error
  double max_mm = 0;          // the largest per-vertex error of any face
  double mean_of_max_mm = 0;  // mean over faces of the per-face max
  double weight_error = 0;    // mean |fitted - true| controller weight
  std::map<std::string, double> expression_mean_mm;  // per expression, over subjects
};

struct RetargetEvaluation {
  bool ground_truth = false;  // false: faces without recipe weights (no scores, only the sheet)
  std::vector<MethodScore> methods;  // in the order given, "dt" first when computed
  std::string metrics_path;          // out/metrics.json
  std::string sheet_path;            // out/contact_sheet.png
  double seconds = 0;
};

RetargetEvaluation evaluate_retargeting(const RetargetEvaluationOptions& options);

}  // namespace retarget
