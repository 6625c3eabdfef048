// Where a rig moves: the vertices its controllers displace, overall and per face region
// (mouth, eyes, brows), so that errors can be measured where an expression happens rather
// than averaged over a head whose back never moves.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "geometry/rig.h"

namespace retarget {

// The face regions errors are reported for. A controller belongs to one region, told from its
// name or from the human blendshapes it stands for (ARKit-style names: jaw, mouth, lip, smile,
// cheek, tongue, nose, sneer -> mouth; eye, blink, squint, lid -> eyes; brow -> brows).
// Returns "mouth", "eyes", "brows" or "" (none of them; such a controller counts only in the
// overall footprint). Case-insensitive; "brow" wins over "eye" (eyeBrowLeftDown is a brow).
std::string face_region_of(const std::string& name);

// Largest displacement of each vertex over `shapes` (each #V x 3) from `rest` (#V x 3), in the
// rest's units. Returns #V values.
Eigen::VectorXd vertex_motion(const Positions& rest, const std::vector<Positions>& shapes);

// Indices of the vertices whose `motion` exceeds max(absolute, relative x the largest motion),
// ascending. Empty when nothing moves.
std::vector<int> moving_vertices(const Eigen::VectorXd& motion, double absolute, double relative = 0.01);

struct RigFootprint {
  Eigen::VectorXd motion;   // #V: largest displacement over the controllers at either end of their range
  std::vector<int> moving;  // vertices any controller moves (moving_vertices of `motion`)
  // region -> the vertices that region's controllers move (same thresholds); only regions with
  // at least one controller and one vertex appear. A vertex may lie in several regions.
  std::map<std::string, std::vector<int>> regions;
  std::map<std::string, std::string> controller_region;  // controller -> region ("" for none)
};

// threshold: the absolute motion below which a vertex counts as still, in rig units (callers
// pass 0.1 mm converted with the eye-distance scale); the relative floor is 1% of the largest.
// controller_names: optional, controller -> the names to classify it by (e.g. the human
// blendshapes of its controller-table row); a controller absent there is classified by its own
// name, and a controller whose listed names disagree takes the region most of them name.
RigFootprint rig_footprint(const Rig& rig, double threshold,
                           const std::map<std::string, std::vector<std::string>>& controller_names = {});

}  // namespace retarget
