// landmarks.png for `retarget avatar init`: the avatar seen from the front and from its left,
// in its own face frame (so a head exported lying down is shown upright), each proposed
// landmark a dot with its name, coloured by confidence, the eye rims tinted, and a title band.
#pragma once

#include "avatar/landmark_proposals.h"
#include "geometry/rig.h"
#include "render/render.h"

namespace retarget {

struct LandmarkSheetOptions {
  int view_size = 640;  // pixels, width and height of each view; 64..4096
  void validate(const std::string& key_path = "landmark_sheet") const;
};

// Size: 2 * view_size x (title band + view_size). Dots: green for confidence >= 0.7, orange for
// >= 0.4, red below. The side view shows the face's left and centre landmarks only.
Image landmark_sheet(const Rig& rig, const LandmarkProposal& proposal, const LandmarkSheetOptions& options = {});

}  // namespace retarget
