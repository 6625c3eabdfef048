// The rig head end to end: fit the controller map (geometry/controller_map.h) to an annotation
// project's champions, and carry human faces onto the rig through it (each face's blendshape
// weights fitted with the face model, geometry/face_model_fit.h, mapped, evaluated on the rig).
// `retarget rig-map fit` and `retarget rig-map apply` are these two calls.
#pragma once

#include <string>
#include <vector>

#include "correspond/belief_search.h"
#include "correspond/controller_map_fit.h"

namespace retarget {

struct RigHeadFitOptions {
  std::string correspondences;  // the correspondence folder (both datasets)
  // Annotation projects whose champions teach the map, in round order: a later round's champion
  // replaces an earlier one's for the same expression (a budget may leave the last round
  // unfinished). Empty: the prior alone.
  std::vector<std::string> annotations;
  std::string prior;         // a controller table (e.g. `avatar meaning`'s); empty: none (ridge to 0)
  ControllerMapOptions map;  // the champions-only fit's prior weight
  // Every decided comparison of every round counts (fit_controller_map_ranked, distances between
  // the faces the rig makes), not only the champions; false: the champions' closed-form fit.
  bool comparisons = true;
  RankingOptions ranking;
  // Choose ranking.prior_weight by cross-validation over the expressions (choose_prior_weight)
  // instead of taking it as given.
  bool choose_prior_weight = true;
  // The map belief's most likely map instead (correspond/belief_rounds.h): every decided comparison of the
  // rounds observed in order from the prior (needed), the belief search's own model of people, then
  // read again against all the others (BeliefSearchOptions::map_reading).
  bool belief = false;
  BeliefSearchOptions belief_search = BeliefSearchOptions::map_reading();
  void validate() const;  // throws retarget::Error naming the option
};

// The fitted map; `pairs` counts the champions used (groups without one are left out). Throws
// retarget::Error when there is neither an annotation nor a prior, the human dataset has no
// recipes, or the prior does not fit the rig and face model.
ControllerMap fit_rig_head(const RigHeadFitOptions& options);

struct RigHeadApplyResult {
  int faces = 0;
  std::string weights_csv;  // out/weights.csv: file, then one column per controller
};

// For every face of the folder written by `retarget faces`: the face model's blendshape weights,
// mapped to the rig's controllers (clamped to their ranges), the rig evaluated there, written as
// out/<stem>.obj with the rig's own faces. The face model is the human dataset's source, the rig
// the avatar dataset's (both found through `correspondences`). Throws retarget::Error for faces
// of another topology, a map naming other controllers than the rig's, or a face-folder dataset.
RigHeadApplyResult apply_rig_head(const ControllerMap& map, const std::string& faces,
                                  const std::string& correspondences, const std::string& out);

}  // namespace retarget
