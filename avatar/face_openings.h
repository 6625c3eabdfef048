// The openings of a face, found from its rig: the rims of holes (an eye socket, lips cut open,
// the neck) and slits, i.e. places where surface points that touch at rest part under a
// controller (lips folded into the mouth, lids or lips stored as a seam of coincident
// vertices). Each is scored by how much the rig opens or closes it; the landmark proposal picks
// the mouth and the eyes among them.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "avatar/rig_welding.h"
#include "geometry/rig.h"

namespace retarget {

struct FaceOpening {
  enum class Kind { hole, slit };
  Kind kind = Kind::hole;
  // hole: the rim in loop order; slit: every vertex of a parting pair (sorted). Welded
  // representatives, i.e. vertex indices of the rig's neutral.
  std::vector<int> vertices;
  std::vector<std::array<int, 2>> pairs;  // slit only: the pairs that part (close at rest)
  int controller = -1;                    // the controller that opens or closes it most
  // How much that controller opens or closes it, in the rig's units. hole: the root mean square
  // of the rim's motion after the best rigid motion of the rim is taken out (a lid closing over a
  // socket scores, an ear bending as a whole does not); slit: the median distance by which its
  // pairs part.
  double opening = 0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // centroid of `vertices` at rest
  double size = 0;                                   // bounding-box diagonal of `vertices` at rest
};

struct FaceOpeningOptions {
  // Slits: pairs closer than slit_radius x the head's bounding-box diagonal at rest, not joined
  // by an edge, that part by more than slit_parting x the controller's largest offset and by more
  // than slit_ratio x their rest distance. Clusters of fewer than min_slit_pairs pairs are noise.
  double slit_radius = 0.012;
  double slit_parting = 0.08;
  double slit_ratio = 3.0;
  int min_slit_pairs = 3;
  // Holes larger than max_hole_size x the head's diagonal are the head's outline (a neck, the
  // rim of a face mask), not openings of the face.
  double max_hole_size = 0.55;
  // A controller counts for a hole only where the rim's non-rigid motion is at least
  // min_hole_share x the controller's largest offset (a jaw opening moves the whole face a
  // little; a blink moves the lid's rim most of all).
  double min_hole_share = 0.1;

  // Throws retarget::Error naming `key_path`.<field> for a value out of range.
  void validate(const std::string& key_path = "openings") const;
};

// The head (the largest connected piece of the welded surface, by vertex count) as #V flags, and
// the other pieces (the parts: eyeballs, teeth, tongue, ...), each a sorted vertex list.
struct HeadAndParts {
  std::vector<char> head;
  std::vector<std::vector<int>> parts;
};
HeadAndParts split_head_and_parts(const Rig& rig, const Weld& weld);

// Every opening of the head, holes first (longest rim first), then slits (per controller, in
// controller order). A rig without controllers has holes with opening 0 and no slits.
std::vector<FaceOpening> find_face_openings(const Rig& rig, const Weld& weld, const std::vector<char>& head,
                                            const FaceOpeningOptions& options = {});

}  // namespace retarget
