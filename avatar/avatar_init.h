// `retarget avatar init`: a complete rig folder for a new avatar, with everything proposed from
// the rig itself (avatar/landmark_proposals.h) for a person to check:
//   rig.yaml        neutral, controllers, the proposed `landmarks:` (each with its confidence and
//                   origin as a comment) and `eyes:`; units; the mirror plane, the face's axes,
//                   the scale (mm per unit by the paper's 10 cm between the eyes) and the parts as
//                   comments;
//   neutral.obj, <controller>.obj   the rig's meshes, vertex for vertex (never welded);
//   proposals.yaml  the same proposals, machine-readable: landmark -> {vertex, confidence, how},
//                   frame, mirror plane, parts (name, kind, vertices), notes;
//   landmarks.png   front and side views with every proposal marked and labelled.
#pragma once

#include <map>
#include <string>

#include "avatar/landmark_proposals.h"
#include "geometry/rig.h"

namespace retarget {

// `rig` with the proposal's landmarks and eyes (replacing any it had).
Rig with_proposed_landmarks(const Rig& rig, const LandmarkProposal& proposal);

// Writes the folder above (created if missing; files of the same names replaced, each
// atomically, rig.yaml last). Throws retarget::Error naming the path that could not be written.
void write_avatar_folder(const std::string& folder, const Rig& rig, const LandmarkProposal& proposal);

// How far each proposed landmark lies from the landmark of the same name in `reference` (a rig
// of the same mesh with hand-picked landmarks), as a fraction of the distance between the
// reference's eye centres (or the proposal's, if the reference has no eyes). Names the
// reference lacks are left out. Throws retarget::Error if the vertex counts differ.
std::map<std::string, double> landmark_distances(const Rig& reference, const LandmarkProposal& proposal);

}  // namespace retarget
