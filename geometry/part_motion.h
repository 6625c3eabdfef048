// Parts that move: an avatar's rigid pieces (eyeballs, teeth, a tongue) sit apart from the skin,
// and DR features, which are differences along the surface, say nothing about where a separate
// piece is: reconstruction keeps each at its rest centroid, so the lower teeth stay put when the
// jaw opens and an eyeball the rig moves does not move. Their motion is read back through the
// rig: the controller weights that best reproduce the reconstructed skin (every vertex outside
// the parts, as it is) and each part's shape about its own centroid (its turn, which its DR
// features do carry, but not its place) are fitted, the rig is evaluated at them, and each part,
// as reconstructed, is moved rigidly (rotation + translation, Kabsch) onto where the rig puts it.
// Its shape stays the reconstruction's; its place and turn are the rig's. Fitting the parts'
// shapes too lets a part whose controllers leave the skin still (an eye's look, an ear's swing)
// move: on the synthetic fox, whose ears swing, the avatar VAE on held-out rig samples went from
// 0.337 to 0.061 mm (x0.47 -> x0.09 of the neutral answer; its parts 1.00 -> 0.12 mm).
#pragma once

#include <memory>
#include <vector>

#include "geometry/mesh.h"
#include "geometry/rig.h"
#include "geometry/rig_weight_fit.h"

namespace retarget {

// The parts to move, each a rigid piece (ascending vertex indices): every connected piece of
// the neutral apart from the skin (the largest), and the rig's named parts (rig.parts) split
// into their connected pieces (one mesh often holds both rows of teeth, which move apart). A
// named part on the skin itself is kept as it is. Pieces of fewer than 3 vertices are left out.
// A skin cut into islands (a texture seam) has its smaller islands placed like parts. Throws
// retarget::Error naming the part and the vertex for a named part's index out of range.
std::vector<std::vector<int>> rig_parts_to_move(const Rig& rig);

class PartMotion {
 public:
  // Copies what it needs of `rig`: the skin's offsets for the fit (the parts' zeroed), and the
  // parts' own rest positions and offsets. parts: vertex lists (each at least 3 vertices, indices
  // in range, disjoint); empty: rig_parts_to_move(rig). Throws retarget::Error for a bad part, or
  // when the parts cover every vertex (no skin to fit).
  explicit PartMotion(const Rig& rig, std::vector<std::vector<int>> parts = {}, const RigWeightFitOptions& fit = {});
  ~PartMotion();

  const std::vector<std::vector<int>>& parts() const { return parts_; }

  // mesh: #V x 3, the rig's vertex order, frame and units (a reconstruction aligned to the rest
  // pose, or held there by anchors). Moves each part in place (first to its rest centroid for the
  // fit, then rigidly onto the rig's); the skin is left as it is.
  // Allocates only the parts' size. Throws retarget::Error for a vertex count other than the rig's.
  void apply(Positions& mesh) const;

 private:
  std::vector<std::vector<int>> parts_;
  // The fit's rig: the skin's offsets as they are, each part's about their mean over the part,
  // so that where the mesh holds a part does not matter to the fit, only its shape.
  std::unique_ptr<Rig> fit_rig_;
  std::unique_ptr<RigWeightFit> fit_;
  std::vector<Positions> part_rest_;                  // per part: #part x 3 neutral positions
  std::vector<Eigen::RowVector3d> part_centroid_;     // per part: the neutral's centroid
  std::vector<std::vector<Positions>> part_offsets_;  // per part, per controller: #part x 3
};

}  // namespace retarget
