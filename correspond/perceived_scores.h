// Simulated annotators who are not the answer key. The evaluation scores against the avatar's
// controller table (which human blendshapes each controller means); an annotator who ranked by
// that very table in rig weights would teach the method the evaluation's answer. People instead
// read the avatar their own way and judge what they see. So each simulated annotator here
//  - reads the table its own way (annotator_reading): every share scaled by its own factor, a
//    share now and then given to a neighbouring shape (same face region and side), a controller
//    with several shapes sometimes read as one of them alone, and now and then one not
//    understood at all;
//  - judges faces, not weights (perceived_scores): a candidate's score is the distance in mm,
//    averaged over the face's regions (mouth, eyes, brows: geometry/rig_footprint.h), between
//    the avatar at the candidate's weights and the avatar the annotator imagines for the human
//    expression (its reading of the table applied to the recipe, on the rig).
// The noise, draws, lapses and fatigue of each judgement are SimulatedAnnotatorOptions'.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "annotate/simulated_annotator.h"
#include "geometry/controller_correspondence.h"

namespace retarget {

struct Correspondences;
struct Dataset;

struct ReadingOptions {
  double share_spread = 0.3;    // each share times exp(N(0, share_spread^2)); >= 0
  double neighbour_rate = 0.1;  // probability that a share goes to a neighbouring shape instead, [0, 1]
  double reread_rate = 0.3;     // probability that a row of several shapes is read as one of them, [0, 1]
  double drop_rate = 0.05;      // probability that a row is not understood (read as empty), [0, 1]

  // Throws retarget::Error naming `key_path`.<field> for a value out of range.
  void validate(const std::string& key_path = "reading") const;
};

// Shapes that a person may take for `shape`: the other shapes of `shapes` with the same leading
// word of the name (mouth, eye, brow, jaw, cheek, nose...) and the same side suffix (_L, _R,
// Left, Right or none). Empty when there is none.
std::vector<std::string> neighbouring_shapes(const std::string& shape, const std::vector<std::string>& shapes);

// One annotator's reading of `table`, drawn from Random(seed) (core/random.h). `shapes`: the
// human blendshape names a share may move to. Rows keep their controllers; shares stay > 0.
ControllerCorrespondence annotator_reading(const ControllerCorrespondence& table,
                                           const std::vector<std::string>& shapes, const ReadingOptions& options,
                                           uint64_t seed);

// Per annotator reading, per group, each candidate's score: the mean over the rig's regions of
// the mean per-vertex distance in mm (eye distance 10 cm) between the rig at the candidate's
// weights and the rig at the reading's weights for the group's recipe. Candidate meshes are built
// once and shared by every reading. Throws retarget::Error when the human dataset has no recipes,
// a group has no recipe, or the avatar has no eyes (no mm) or rig weights.
std::vector<CandidateScores> perceived_scores(const Correspondences& correspondences, const Dataset& human,
                                              const Dataset& avatar,
                                              const std::vector<ControllerCorrespondence>& readings);

}  // namespace retarget
