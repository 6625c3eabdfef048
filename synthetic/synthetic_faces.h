// The bundled synthetic default (`retarget synth`): a procedural human face model and three
// stylized avatars with their own topologies, rigs and a ground-truth table saying which human
// blendshapes each avatar controller stands for. Everything is built in code, deterministically
// for a seed, and written in the formats users bring (face_model.yaml, rig.yaml folders).
//
// Frames and units (human and avatars): cm, +y up, +z towards the viewer, +x the face's own
// left (so `_L` / `Left` shapes move the +x side).
//
// The human (synthetic_human):
//   - one topology of ~7,400 vertices: a graded quad grid over (azimuth, height) wrapped
//     around the front of an ellipsoidal head (~21 cm from under the chin to the top of the
//     forehead, ~15 cm wide), eye centres ~6.3 cm apart, mouth ~4.6 cm wide;
//   - the grid is cut along each eye (the lids are separate rows of vertices, open at rest)
//     and along the mouth (upper and lower lip rows coincide at rest and part when the jaw
//     opens); separate parts: an eyeball cap behind each eye opening (with a liner that flares
//     under the skin around it) and a mouth pocket behind the lips (seen from inside, so an
//     open mouth shows a cavity), both moving with the face;
//   - identities: ~29 modes, each one standard deviation of a named proportion (face width,
//     jaw width, nose length, eye spacing, lip thickness, chin, asymmetries, ...);
//   - expressions: the 45 ARKit-style names of synthetic_expression_names() (every name the
//     default recipes configs/expressions/facewarehouse47.yaml use), smooth displacement
//     fields over the face's own (azimuth, height) layout, identical for every identity
//     (mouthClose, as in ARKit, is meant on top of jawOpen);
//   - 40 named landmarks (synthetic_landmark_names()) and eye vertex sets (the lid margins).
// The seed moves the model's mean face by about half a standard deviation per identity mode;
// the modes' meaning and every expression field stay the same.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "geometry/controller_correspondence.h"
#include "geometry/face_model.h"
#include "geometry/rig.h"

namespace retarget {

// The human face model for `seed`. Deterministic: the same seed gives identical numbers.
FaceModel synthetic_human(uint64_t seed = 1);

// The 45 expression names of the synthetic human, in its order (sorted).
const std::vector<std::string>& synthetic_expression_names();

// Landmark names of the synthetic human (left = +x side). The avatars use the same names for
// the features they have.
const std::vector<std::string>& synthetic_landmark_names();

struct SyntheticAvatar {
  Rig rig;                                  // neutral, controllers (ranges [0, 1]), landmarks, eyes
  ControllerCorrespondence correspondence;  // a row for every controller; {} = no human counterpart
  std::string description;                  // one line, for the README and the summary
};

// The stylized avatars, each with its own topology and proportions (cm, the frame above):
//   moppet: a round chibi head (closed latitude-longitude sphere, ~3,300 vertices), huge eyes,
//           a tiny mouth; 21 controllers (headSquash, eyePop without human counterparts);
//   fox:    an open square grid mapped onto a domed disc (~4,100 vertices) with a long snout
//           and two cone ears; 22 controllers (ear wiggles, earsBack, snoutTwitch without);
//   glorp:  a wide, flat ellipsoid whose poles are its left and right ends (~4,300 vertices),
//           a wide grin, protruding far-apart eyes, two antennae; 17 controllers (throatPuff,
//           antenna bends without).
// Each has eyelids and lips cut like the human's, eyeball caps, a mouth pocket, landmarks named
// like the human's and eye vertex sets. They do not depend on the seed.
std::vector<SyntheticAvatar> synthetic_avatars();

// The set `retarget synth` writes: the human, the three avatars above, and bramble, the fox
// dressed with many parts (synthetic/avatar_trim.h: lashes, brows, irises, teeth, a tongue, the
// skin in two islands), for checking what an artist's many-part head does to the method.
struct SyntheticSet {
  uint64_t seed = 1;
  FaceModel human;
  std::vector<SyntheticAvatar> avatars;
};
SyntheticSet synthetic_set(uint64_t seed = 1);

// Writes the set below `folder` (created if missing; existing files are replaced):
//   human/face_model.yaml (+ neutral.obj, identities/*.obj, expressions/*.obj)
//   avatars/<name>/rig.yaml (+ neutral.obj, <controller>.obj) and avatars/<name>/correspondence.yaml
//   README.txt (what is where, the seed, counts)
void write_synthetic_set(const std::string& folder, const SyntheticSet& set);

}  // namespace retarget
