// The table `retarget pipeline` ends with: from the evaluation's metrics.json, each method's error
// on each set (references, blends) beside the neutral answer, in mm over moving vertices and in
// active rig weights, each as a multiple of the neutral answer's.
#pragma once

#include <string>

namespace retarget {

// The table as text, or "" when `metrics_json` does not exist. Throws retarget::Error naming the
// file when it is not the evaluation's JSON.
std::string evaluation_summary(const std::string& metrics_json);

}  // namespace retarget
