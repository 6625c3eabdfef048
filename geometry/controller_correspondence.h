// Ground truth for evaluation: which human blendshapes each avatar controller stands for.
// A table row `smileLeft: {mouthSmile_L: 1.0}` says that smileLeft at weight 1 is the avatar's
// version of the human mouthSmile_L at weight 1; `browUpLeft: {browInnerUp_L: 1, browOuterUp_L: 1}`
// says that one controller covers two human shapes; `earWiggle: {}` has no human counterpart.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "geometry/rig.h"

namespace retarget {

// controller name -> (human blendshape name -> weight)
using ControllerCorrespondence = std::map<std::string, std::map<std::string, double>>;

// correspondence.yaml:
//   avatar: moppet                 # optional, informational
//   human: synthetic-human         # optional, informational
//   controllers:
//     smileLeft: {mouthSmile_L: 1.0}
//     earWiggle: {}                # (or `earWiggle:` with no value)
// Throws retarget::Error naming the file, line and key for: a missing or unreadable file, no
// `controllers` map, a row that is not a map, a weight that is not a finite number, unknown
// top-level keys.
ControllerCorrespondence load_controller_correspondence(const std::string& path);

// Writes the table in the format above, atomically; `header` lines are written as # comments.
void write_controller_correspondence(const std::string& path, const ControllerCorrespondence& table,
                                     const std::string& avatar, const std::string& header = "");

// Throws retarget::Error(where, ...) for a row naming a controller not in `controllers` or a
// human shape not in `blendshapes` (listing the unknown name), and for a controller missing
// from the table.
void check_controller_correspondence(const ControllerCorrespondence& table, const std::vector<std::string>& controllers,
                                     const std::vector<std::string>& blendshapes, const std::string& where);

// The avatar controller weights that best reproduce human blendshape weights through the table:
// y = argmin |A y - w|^2 with A[h][c] = table[c][h], over the controllers with a non-empty row
// (a tiny ridge keeps it unique), then clamped to [lo, hi]. When no human shape appears in two
// rows (the synthetic avatars' tables), this is y_c = sum_h table[c][h] w_h / sum_h table[c][h]^2.
// human_weights: blendshape -> weight (names absent from the table are ignored). Returns a weight
// for every controller of the table (0 for rows without a human counterpart).
std::map<std::string, double> controller_weights_from_human(const ControllerCorrespondence& table,
                                                            const std::map<std::string, double>& human_weights,
                                                            double lo = 0.0, double hi = 1.0);

// The ground-truth weight vector of `rig` for a human face: controller_weights_from_human clamped
// to each controller's range, in the rig's controller order (0 for controllers the table lacks).
Eigen::VectorXd rig_weights_from_human(const ControllerCorrespondence& table, const Rig& rig,
                                       const std::map<std::string, double>& human_weights);

}  // namespace retarget
