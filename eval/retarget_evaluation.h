// The end-to-end check on faces with ground truth: human test meshes (data/test_faces.h) carried
// onto the avatar by several methods (retarget-infer outputs of full and stage-1 bundles, and
// deformation transfer alone, computed here), each compared with the avatar expression the
// controller table says is right: the recipe's blendshape weights mapped to controller weights
// (geometry/controller_correspondence.h) and evaluated on the rig.
//
// The faces may hold two sets (data/test_faces.h): the reference expressions the correspondences
// were built on, and random blends nobody annotated (unseen expressions); each is scored apart
// as well as together.
//
// Every figure stands beside the trivial answer: the method "neutral" (the avatar's rest mesh
// for every face) is scored first, and each method's errors are also given as a fraction of
// the neutral's. Deformation transfer alone ("dt") and DT projected onto the rig ("dt_rig": the
// rig evaluated at the controller weights that best reproduce the DT result) are the two
// geometric baselines.
//
// Errors: per-vertex distance in mm (avatar scaled so its eye centres are 10 cm apart) after a
// rigid alignment of each output onto its ground truth, averaged over every vertex, over the
// vertices the rig moves (geometry/rig_footprint.h: > 0.1 mm under some controller) and over
// each face region's vertices (mouth, eyes, brows: the footprints of the controllers of that
// region). In rig-weight space, the controller weights fitted to the output as written
// (geometry/rig_weight_fit.h; retarget-infer aligns its outputs to the rest pose, deformation
// transfer keeps the rest's frame) against the ground-truth weights: the mean absolute
// difference over all controllers (which all-zero weights do well on when most controllers
// rest), over the controllers active (> 0.05) in either answer, and relative to the truth's own
// weights (sum |fitted - true| / sum |true|: 1 for all-zero weights).
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
  std::string out;             // metrics.json, contact_sheet.png and dt/ (the DT meshes) go here
  bool neutral = true;         // add the method "neutral": the avatar's rest mesh for every face
  bool rig_projection = true;  // with deformation_transfer: add "dt_rig", DT projected onto the rig
  int sheet_rows = 8;          // faces on the contact sheet (distinct expressions), >= 1
  // Which faces the sheet shows: "worst" (the expressions where `sheet_method` is furthest from
  // the truth over the moving vertices, worst first) or "first" (one per expression in order).
  std::string sheet = "worst";
  std::string sheet_method;  // empty: the last method given (or dt)
  int render_size = 256;     // pixels per picture on the sheet
  void validate() const;     // throws retarget::Error naming the option
};

struct MethodScore {
  std::string name;
  int samples = 0;
  double mean_mm = 0;                       // mean over faces of the mean per-vertex error
  double moving_mm = 0;                     // the same over the vertices the rig moves
  double max_mm = 0;                        // the largest per-vertex error of any face
  double mean_of_max_mm = 0;                // mean over faces of the per-face max
  std::map<std::string, double> region_mm;  // "mouth", "eyes", "brows" -> mean over the region's vertices
  double weight_error = 0;                  // mean |fitted - true| controller weight, over all controllers
  double weight_error_active = 0;           // the same over controllers > 0.05 in either answer (faces with any)
  double weight_error_relative = 0;         // sum |fitted - true| / sum |true| (faces whose truth moves); neutral: 1
  // This method's figures as fractions of the neutral answer's (1 = no better than doing nothing;
  // NaN without the neutral method).
  double fraction_of_neutral = 0, moving_fraction_of_neutral = 0, weight_active_fraction_of_neutral = 0;
  // Identity independence (Fig. 11): per expression, how far each person's output lies from the
  // mean output of everyone with that expression (mm over moving vertices), averaged; the truth's is 0.
  double identity_spread_mm = 0;
  std::map<std::string, double> expression_mean_mm;    // per expression, over subjects
  std::map<std::string, double> expression_moving_mm;  // per expression, over the moving vertices
};

struct RetargetEvaluation {
  bool ground_truth = false;  // false: faces without recipe weights (no scores, only the sheet)
  // "neutral", "dt", "dt_rig" first when computed, then the methods in the order given.
  std::vector<MethodScore> methods;
  // The same figures per set of faces (data/test_faces.h: "references", "blends") when the faces
  // hold more than one set; each set's fractions are of the neutral answer on that set.
  std::map<std::string, std::vector<MethodScore>> sets;
  int moving_vertices = 0;  // of the avatar's vertex count
  std::map<std::string, int> region_vertices;
  std::vector<std::string> sheet_expressions;  // the faces on the sheet, as "subject expression"
  std::string metrics_path;                    // out/metrics.json
  std::string table_path;                      // out/comparison.csv: a row per method and set (with ground truth)
  std::string sheet_path;                      // out/contact_sheet.png
  double seconds = 0;
};

RetargetEvaluation evaluate_retargeting(const RetargetEvaluationOptions& options);

}  // namespace retarget
