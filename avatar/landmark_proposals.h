// Landmarks proposed from the rig alone (`retarget avatar init`): the mirror plane gives the
// face's left-right axis; the openings that the rig opens and closes give the mouth (the
// strongest opening on the plane) and the eyes (the strongest mirrored pair); the line from the
// mouth to the eyes gives "up", and the side the eyes sit on gives "forward". Landmarks are then
// read off those openings the way the human face models define them:
//   mouth_left / mouth_right      the mouth's rim at its extremes along the left axis (where the
//                                 lips meet);
//   lip_upper_center / _lower_    the rim's upper and lower vertices nearest the mirror plane,
//                                 the frontmost for a slit (the lips' line, not the mouth's inside);
//   eye_inner_* / eye_outer_*     each eye opening's extremes along the left axis;
//   eyelid_upper_* / _lower_*     the upper and lower rim vertices midway between the corners;
//   nose_tip                      the frontmost head vertex near the plane between the mouth and
//                                 the eyes;
//   chin                          on the mirror plane's profile below the lower lip (face_profile.h),
//                                 the chin's furthest point towards the front and below (gnathion)
//                                 if it reaches further that way than the lower lip, else (a
//                                 receding jaw, a snout) the jaw's lowest point before the profile
//                                 rises towards the throat (menton);
//   brow_inner_* / _middle_* /    the brow above each eye as the controllers that move that region
//   brow_outer_*                  and not the lids show it: the middle on the brow ridge's crest
//                                 where they lift it most, the ends the extremes along the left axis
//                                 of what they lift by a quarter of that or more (and at least three
//                                 times as much as the other brow's controllers do), at about the
//                                 middle's height.
// "left" is the face's own left (the human models' convention: mouth_left is on the +x side of
// a face looking along +z with +y up). Upper and lower sides of a rim are told apart by the
// surface each rim edge belongs to (its triangle lies above or below the rim), which works for
// open holes, cut seams and folded lips alike.
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

#include "avatar/face_openings.h"
#include "avatar/mirror_plane.h"
#include "avatar/rig_welding.h"
#include "geometry/rig.h"

namespace retarget {

// The face's frame, in the rig's coordinates: orthonormal, right-handed (left = up x forward).
struct FaceFrame {
  Eigen::Vector3d left = Eigen::Vector3d::UnitX();
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  Eigen::Vector3d forward = Eigen::Vector3d::UnitZ();
};

struct ProposedLandmark {
  int vertex = -1;
  // 0..1: how sure the proposal is (mirror agreement of paired landmarks, distance from the
  // plane of centre landmarks, how clearly the opening it comes from stands out).
  double confidence = 0;
  std::string how;  // one line: where it came from
};

struct ProposedPart {
  enum class Kind { eye, teeth, mouth, other };  // mouth: inside the mouth, teeth/tongue/cavity not told apart
  Kind kind = Kind::other;
  std::string name;           // eye_left, eye_right, teeth_left, mouth_1, part_3, ...
  std::vector<int> vertices;  // sorted
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
};
const char* part_kind_name(ProposedPart::Kind kind);

struct LandmarkProposalOptions {
  WeldOptions weld;
  MirrorPlaneOptions mirror;
  FaceOpeningOptions openings;
  // Throws retarget::Error naming the key path of a bad field.
  void validate(const std::string& key_path = "avatar") const;
};

struct LandmarkProposal {
  MirrorPlane mirror;
  FaceFrame frame;
  std::map<std::string, ProposedLandmark> landmarks;
  EyeLandmarks eyes;                         // the two eye openings' rims (their centroids: the eye centres)
  double eye_distance = 0;                   // between the eye centres, rig units
  std::vector<ProposedPart> parts;           // every piece other than the head
  int welded = 0;                            // vertices merged with another for the maths
  std::string mouth_controller;              // the controller that opens the mouth most
  std::vector<std::string> eye_controllers;  // left, right: the controllers that close each eye most
  std::vector<std::string> notes;            // what was found and what was not, for the user
};

// Throws retarget::Error, naming the rig's source and saying what could not be found and how to
// supply it, for: an empty rig, a rig without controllers (nothing to witness the openings), no
// mirror symmetry, no opening on the mirror plane that a controller opens (no mouth), no mirrored
// pair of openings (no eyes).
LandmarkProposal propose_landmarks(const Rig& rig, const LandmarkProposalOptions& options = {});

}  // namespace retarget
