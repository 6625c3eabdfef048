// How well a trained VAE reconstructs meshes, measured as the paper's Table 1 does: the mean
// and max per-vertex error in millimetres, with the mesh scaled so that its two eye centres
// are 10 cm apart, through the whole path
//   DR features -> normalise -> VAE (codes = means) -> denormalise -> mesh (reconstruction)
//   -> rigid alignment onto the ground truth -> per-vertex distance.
//
// Ground truth: avatars: the rig's own meshes for the stored weights when the rig the dataset
// was built from is still readable (and has the same topology), else the meshes rebuilt from
// the stored features; humans: the identity-averaged expression each input maps to (the
// human VAE's target), rebuilt from its features.
//
// Every figure stands beside the trivial answers, scored through the same alignment and
// metric (geometry/expression_error.h): the neutral answer (the dataset's rest mesh for every
// sample; for a human dataset the mean face) and, for human datasets, the mean-expression
// answer (one mesh for every sample, reconstructed from the mean of the raw targets over the
// training split's samples). A VAE that does not beat them has learnt nothing useful, however
// plausible its millimetres look.
//
// Errors are also averaged over the moving vertices only (a head whose back never moves
// dilutes every mean): the vertices the rig's controllers move by more than 0.1 mm
// (rig_footprint) when the dataset's rig loads, else those the ground-truth meshes (avatars:
// of the split's samples; humans: every expression's identity-averaged target) move by more
// than 0.1 mm from the rest (geometry/rig_footprint.h, 1% relative floor).
#pragma once

#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "data/dataset.h"
#include "models/mesh_vae.h"

namespace retarget {

struct VaeEvaluationOptions {
  std::string split = "test";  // "test", "train" or "all"
  int64_t batch = 64;          // samples per network batch
  // What the decoder was trained to produce (VaeDataOptions::target_normaliser of the run):
  // human datasets decode in their targets' ranges ("targets") or the shared ones ("shared").
  std::string target_normaliser = "targets";
  // Avatars: hold the vertices the dataset never moves at rest when rebuilding meshes
  // (data/still_vertices.h), as the retargeting bundle does.
  bool anchors = true;
  // Avatars with a rig: move the rigid parts (eyeballs, teeth) where the rig puts them for the
  // rebuilt skin (geometry/part_motion.h), as the bundle does; off: they stay at rest. Either
  // way, the parts' own error is reported as the region "parts", and each eye, teeth or tongue
  // part the rig names as "part <name>".
  bool part_motion = true;
  void validate() const;
};

// A trivial answer scored like the VAE. Millimetres (eye distance 10 cm), or mesh units when
// the dataset has no eyes (VaeEvaluation::unit); per-sample figures averaged over the samples.
struct TrivialScore {
  std::string name;                           // "neutral" or "mean_expression"
  double mean = 0;                            // mean per-vertex error after rigid alignment onto the truth
  double mean_of_max = 0;                     // the per-sample maximum, averaged over the samples
  double max = 0;                             // the largest per-vertex error of any sample
  double moving_mean = 0;                     // mean over the moving vertices (= mean when none move)
  std::map<std::string, double> region_mean;  // "mouth", "eyes", "brows" (rig footprint only)
  // Mean |answer - target| of the normalised features, as VaeEvaluation::feature_l1: neutral:
  // normalise(zeros); mean expression: the normalised mean target.
  double feature_l1 = 0;
};

struct VaeEvaluation {
  std::string split;
  int64_t samples = 0;
  int vertices = 0;
  std::string ground_truth;   // what the meshes were compared with (see above)
  std::string unit = "mm";    // "mm" (eye distance 10 cm), or "units" when the dataset has no eyes
  double unit_scale = 1;      // millimetres per mesh unit
  double mean = 0;            // mean per-vertex error over all samples and vertices
  double max = 0;             // the largest per-vertex error of any sample
  double mean_of_max = 0;     // the per-sample maximum, averaged over the samples
  int64_t worst_sample = -1;  // dataset row of `max`
  int worst_vertex = -1;
  double feature_l1 = 0;  // mean |reconstruction - target| of the normalised features
  double seconds = 0;

  // Where expressions happen (see above): how the moving vertices were found ("rig
  // controllers" or "ground-truth meshes") and how many there are (0: nothing moves, and the
  // moving means equal the means).
  std::string footprint;
  int moving_vertices = 0;
  double moving_mean = 0;                     // the VAE's mean per-vertex error over the moving vertices
  std::map<std::string, double> region_mean;  // per face region (rig footprint only)

  // The trivial answers, neutral first, then (human datasets) "mean_expression".
  std::vector<TrivialScore> trivial;
  // mean / neutral mean and moving_mean / neutral moving_mean: below 1 beats doing nothing
  // (NaN when the neutral answer's error is 0).
  double fraction_of_neutral = std::numeric_limits<double>::quiet_NaN();
  double moving_fraction_of_neutral = std::numeric_limits<double>::quiet_NaN();
  // The trivial answer called `name`, or nullptr.
  const TrivialScore* trivial_answer(const std::string& name) const;

  // Human datasets: do codes of one expression gather across people? Mean distance between
  // the codes (means) of the same expression of two different test subjects, and between
  // codes of two different expressions; their ratio (within / between, smaller is better).
  double within_expression = std::numeric_limits<double>::quiet_NaN();
  double between_expression = std::numeric_limits<double>::quiet_NaN();
  double code_distance_ratio = std::numeric_limits<double>::quiet_NaN();
};

// Evaluates `vae` (put in eval mode) on a split of `dataset`. Throws retarget::Error for an
// empty split or a VAE of another vertex count.
VaeEvaluation evaluate_vae(MeshVaeImpl& vae, const Dataset& dataset, const VaeEvaluationOptions& options = {});

}  // namespace retarget
