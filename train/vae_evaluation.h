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
#pragma once

#include <cstdint>
#include <limits>
#include <string>

#include "models/mesh_vae.h"
#include "train/dataset.h"

namespace retarget {

struct VaeEvaluationOptions {
  std::string split = "test";  // "test", "train" or "all"
  int64_t batch = 64;          // samples per network batch
  void validate() const;
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
