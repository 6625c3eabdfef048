// The bundled avatars of synthetic_faces.h as tables (avatar_spec.h) and synthetic_avatars().
// Numbers are cm and radians; "left" is +x, the right side its mirror image.
#include "synthetic/avatar_spec.h"

namespace retarget {

namespace synth {

namespace {

// Short names for the rows.
constexpr Anchor kLine = Anchor::kMouthLine, kCorner = Anchor::kMouthCorner;
constexpr Motion kNormal = Motion::kNormal, kUpperLip = Motion::kUpperLip;
constexpr Sides kOne = Sides::kOne, kPair = Sides::kPair, kSummed = Sides::kSummed;

// Smiles and frowns are anchored at the mouth corner, offset by a share of their radii: a
// smile (0.15 rx, 0.1 ry) outside and above it, a frown 0.1 ry below. The products are written
// out (0.15 * 1.6) so the numbers stay those the avatars were first built with.

// ------------------------------------------------------------------------------------------
// moppet: a round chibi head on a latitude-longitude sphere, huge eyes, a tiny mouth.

constexpr double kMoppetA = 9.0, kMoppetB = 8.4, kMoppetC = 8.6;  // head semi-axes

const AvatarSpec kMoppet = {
    "moppet",
    "round chibi head (latitude-longitude sphere), huge eyes, tiny mouth",
    {GridKind::kSphere,
     // 64 longitudes, densest at the front; 45 latitudes, densest just below the equator.
     {-M_PI, M_PI, 65, {4.0, 0, 0.64, true}, true, 0, true, Mapping::kLinear, kMoppetA},
     {-M_PI / 2, M_PI / 2, 45, {2.5, -0.2, 0.6}, false, 0, false, Mapping::kLinear, kMoppetB}},
    // eyes: centre, half width; falls; open lids; ball radius, recess, lid, cornea; liner; cap
    {4.1, -0.8, 2.5, 3.4, 2.7, {1.6, 1.3}, 3.05, -0.1, 0.3, 0.18, {0.8, -0.1}, 8, 22},
    // mouth: y, corner; taper, rise, band, band growth, reach, floor, floor fade; pocket
    {-4.6, 1.0, 0.75, 0.3, 0.8, 0.3, 3.0, -9.5, 3.5, 9, 8, 1.08, 0.55, 1.3},
    {SurfaceKind::kEllipsoid, kMoppetA, kMoppetB, kMoppetC},
    {},
    {BumpRelief{0.55, {4.6, -3.9, 2.0, 1.6, Anchor::kFace, true}},                 // cheeks
     BumpRelief{0.35, {0, -3.0, 0.55, 0.45}},                                      // nose
     BumpRelief{0.3, {4.1, 3.5, 1.9, 0.45, Anchor::kFace, true}},                  // brows
     BumpRelief{2.2, {kMoppetA * M_PI / 2, -0.8, 1.7, 2.4, Anchor::kFace, true}},  // the sides, a quarter turn round
     BumpRelief{0.18, {0, 0, 1.5, 0.6, kLine}},                                    // lips
     BumpRelief{0.2, {0, -6.3, 2.0, 1.0}},                                         // chin
     BumpRelief{0.9, {0, kMoppetB * 1.2, 3.0, 1.6}}},                              // crown
    {},
    {{"blink", kPair, Lids{{-0.9, 0.9}}, {"eyeBlink_L"}},
     {"squint", kPair, Lids{{0.95, 0.75}}, {"eyeSquint_L"}},
     {"eyeWide", kPair, Lids{{2.1, 1.5}}, {"eyeWide_L"}},
     {"browUp", kPair, Displacement{{{0.8, {4.1, 3.5, 2.8, 1.8}, {0, 1, 0.05}}}}, {"browInnerUp_L", "browOuterUp_L"}},
     {"browDown", kPair, Displacement{{{0.5, {3.9, 3.3, 2.6, 1.2}, {-0.35, -1, 0.2}}}}, {"browDown_L"}},
     {"smile",
      kPair,
      Displacement{{{1, {0.15 * 1.6, 0.1 * 1.5, 1.6, 1.5, kCorner}, {0.35, 0.5, -0.1}}}},
      {"mouthSmile_L"}},
     {"frown", kPair, Displacement{{{0.4, {0, -0.1 * 1.5, 1.5, 1.5, kCorner}, {0.1, -1, 0}}}}, {"mouthFrown_L"}},
     {"mouthOpen", kOne, Jaw{{0, -3.0, 2.0}, 0.25}, {"jawOpen"}},
     {"pucker", kOne, Pucker{0.3, {0, 0, 1.6, 1.1, kLine}, 0.5, {0, 0, 1.6, 1.1, kLine}}, {"mouthPucker"}},
     {"mouth", kPair, Displacement{{{1, {0, 0, 2.2, 1.5, kLine}, {0.6, 0, 0}}}}, {"mouthLeft"}},
     {"cheeksPuff",
      kOne,
      Displacement{{{0.9, {4.4, -4.0, 2.3, 1.9, Anchor::kFace, true}, {}, kNormal}}},
      {"cheekPuff_L", "cheekPuff_R"}},
     // Without human counterparts: a cartoon squash of the whole head, and eyes that pop.
     {"headSquash", kOne, Squash{{0, -kMoppetB, 0}, {0.08, -0.14, 0.08}}, {}},
     {"eyePop", kOne, EyePop{1.25}, {}}},
    {{"brow_inner_left", 2.6, 3.4},
     {"brow_middle_left", 4.1, 3.6},
     {"brow_outer_left", 5.6, 3.3},
     {"nose_tip", 0, -3.0},
     {"cheek_left", 4.6, -3.9},
     {"chin", 0, -6.4},
     {"forehead", 0, 5.8},
     {"temple_left", 7.2, 1.8},
     {"jaw_left", 4.0, -6.6}}};

// ------------------------------------------------------------------------------------------
// fox: an open front-facing grid mapped onto a domed disc, a long snout and two cone ears.

const AvatarSpec kFox = {
    "fox",
    "open grid on a domed disc, long snout, cone ears",
    {GridKind::kOpen,
     {-8.5, 8.5, 61, {}, true},  // evenly spaced
     {-9.0, 9.0, 57, {}}},
    {3.5, 1.8, 1.4, 2.0, 1.3, {0.75, 0.55}, 1.75, 0.2, 0.2, 0.15, {1.6, 0.3}, 6, 16},
    {-5.0, 2.0, 1.1, 0.3, 0.9, 0.3, 4.5, -1e9, 2, 13, 8, 1.08, 1.2, 2.2, 0.35},
    // The square grid on an elliptical disc (half axes 9.5 x 10 cm) domed forwards.
    {SurfaceKind::kDomedDisc, 9.5, 10.0, 7.0, 8.5, 9.0, 1.04, 0.2},
    {},
    // A long snout: a ridge from the forehead to the nose at its tip, then down to the chin.
    {RidgeRelief{{-8.5, -7.5, -6.2, -5.0, -4.1, -3.3, -2.0, 0.0, 1.6},
                 {0, 0.3, 1.6, 3.1, 4.6, 5.4, 4.0, 1.6, 0},
                 {-7.0, -5.0, -3.3, -1.0, 1.5},
                 {2.6, 1.8, 1.3, 2.2, 2.6},
                 1.6},
     BumpRelief{0.7, {0, -3.3, 0.9, 0.7}},                         // nose
     BumpRelief{0.4, {1.3, -4.4, 1.1, 0.9, Anchor::kFace, true}},  // muzzle
     BumpRelief{0.7, {5.2, -2.2, 2.6, 2.6, Anchor::kFace, true}},  // cheeks
     BumpRelief{0.45, {3.3, 3.5, 1.9, 0.6, Anchor::kFace, true}},  // brows
     BumpRelief{-0.7, {3.5, 1.8, 2.3, 1.9, Anchor::kFace, true}},  // eye sockets
     BumpRelief{0.2, {0, 0, 2.2, 0.5, kLine}},                     // lips
     BumpRelief{0.4, {0, -6.6, 1.8, 1.0}}},                        // chin
    // Ears: flattened cones standing on the top corners of the face.
    EarsSpec{7, 14, {5.3, 7.2}, 0.5, {0.35, 1.0, -0.15}, 5.8, 1.9, 0.6, 0.8},
    {{"blink", kPair, Lids{{-0.4, 0.4}}, {"eyeBlink_L"}},
     {"squint", kPair, Lids{{0.4, 0.3}}, {"eyeSquint_L"}},
     {"browUp", kPair, Displacement{{{0.6, {3.3, 3.6, 2.4, 1.6}, {0, 1, 0.05}}}}, {"browInnerUp_L", "browOuterUp_L"}},
     {"browDown", kPair, Displacement{{{0.45, {3.0, 3.7, 2.2, 1.1}, {-0.35, -1, 0.2}}}}, {"browDown_L"}},
     {"smile",
      kPair,
      Displacement{{{1, {0.15 * 2.0, 0.1 * 1.8, 2.0, 1.8, kCorner}, {0.35, 0.55, -0.15}}}},
      {"mouthSmile_L"}},
     {"frown", kPair, Displacement{{{0.5, {0, -0.1 * 1.6, 1.8, 1.6, kCorner}, {0.1, -1, 0}}}}, {"mouthFrown_L"}},
     {"snarl",
      kPair,
      Displacement{{{1, {1.0, -2.0, 1.4, 1.3}, {0, 0.3, 0.1}},  //
                    {1, {1.3, 0.5, 1.6, 1.3, kLine}, {0, 0.45, 0.05}, kUpperLip}}},
      {"noseSneer_L", "mouthUpperUp_L"}},
     {"jawOpen", kOne, Jaw{{0, -3.5, 2.5}, 0.35}, {"jawOpen"}},
     {"pucker", kOne, Pucker{0.3, {0, 0, 2.6, 1.4, kLine}, 0.5, {0, 0, 2.6, 1.4, kLine}}, {"mouthPucker"}},
     {"cheekPuff", kPair, Displacement{{{0.9, {4.0, -4.5, 2.2, 2.0}, {}, kNormal}}}, {"cheekPuff_L"}},
     // Without human counterparts: ears and a snout twitch.
     {"earWiggle", kPair, PartSwing{0.45}, {}},
     {"earsBack", kOne, PartsBack{0.6}, {}},
     {"snoutTwitch", kOne, Displacement{{{1, {0, -3.3, 1.8, 1.5}, {0.5, 0.2, 0}}}}, {}}},
    {{"brow_inner_left", 2.2, 3.4},
     {"brow_middle_left", 3.3, 3.6},
     {"brow_outer_left", 4.5, 3.4},
     {"nose_tip", 0, -3.3},
     {"nose_bridge", 0, 1.2},
     {"cheek_left", 5.2, -2.2},
     {"chin", 0, -6.6},
     {"forehead", 0, 5.5},
     {"temple_left", 6.2, 3.0},
     {"jaw_left", 4.5, -6.5}}};

// ------------------------------------------------------------------------------------------
// glorp: a wide, flat ellipsoid whose poles are its left and right ends (rings about the x
// axis), a wide grinning mouth, small protruding eyes far apart, two antennae.

constexpr double kGlorpA = 12.0, kGlorpB = 5.5, kGlorpC = 6.5;

const AvatarSpec kGlorp = {
    "glorp",
    "wide flat ellipsoid (poles at its sides), wide grin, protruding far-apart eyes, antennae",
    {GridKind::kSideways,
     // 71 rings along x, densest in the middle; 52 lines around, densest above the front.
     {0, M_PI, 71, {1.2, M_PI / 2, 0.7}, true, M_PI / 2, false, Mapping::kCosine, kGlorpA},
     {-M_PI, M_PI, 53, {2.5, 0.2, 0.7}, false, 0, true, Mapping::kLinear, kGlorpB}},
    {6.0, 3.6, 1.45, 1.7, 1.2, {0.9, 0.7}, 1.8, -0.6, 0.28, 0.12, {0.6, -0.3}, 7, 18},
    {-0.9, 7.0, 3.0, 0.2, 1.0, 0.3, 9.5, -8.5, 2, 21, 8, 1.08, 0.9, 2.0},
    {SurfaceKind::kSidewaysEllipsoid, kGlorpA, kGlorpB, kGlorpC, 1, 1, 1, 0, 0.35},
    // The grin: the mouth line rises towards the corners.
    {0.9, 7.0, 4.5, 8, 11},
    {BandRelief{0.3, {0.7, 5.5, 7.5}},                                // lips
     BumpRelief{0.5, {0, -3.6, 5.5, 1.8}},                            // throat
     BumpRelief{-0.18, {0.9, 1.5, 0.35, 0.25, Anchor::kFace, true}},  // nostrils
     BumpRelief{0.3, {6.0, 5.7, 1.8, 0.5, Anchor::kFace, true}},      // brows
     BumpRelief{0.35, {8.5, -0.5, 2.0, 2.0, Anchor::kFace, true}}},   // cheeks
    // Antennae: thin stalks with a bulb, bending about the base.
    AntennaeSpec{10, 8, {2.4, 1.2 * kGlorpB}, 0.2, {0.35, 0.5, 0}, 5.5, 0.3, 0.5, 0.5, 0.86, 0.16, 0.5},
    {{"blink", kPair, Lids{{-0.5, 0.5}}, {"eyeBlink_L"}},
     {"browUp", kPair, Displacement{{{0.5, {6.0, 5.6, 2.4, 1.5}, {0, 1, 0.05}}}}, {"browInnerUp_L", "browOuterUp_L"}},
     {"browsDown",
      kSummed,
      Displacement{{{0.4, {5.8, 5.5, 2.4, 1.2}, {-0.35, -1, 0.2}}}},
      {"browDown_L", "browDown_R"}},
     {"smile",
      kPair,
      Displacement{{{1, {0.15 * 2.8, 0.1 * 2.8, 2.8, 2.8, kCorner}, {0.4, 0.6, -0.1}}}},
      {"mouthSmile_L"}},
     {"frown", kPair, Displacement{{{0.55, {0, -0.1 * 2.0, 2.4, 2.0, kCorner}, {0.1, -1, 0}}}}, {"mouthFrown_L"}},
     {"mouthOpen", kOne, Jaw{{0, -1.0, -3.5}, 0.35}, {"jawOpen"}},
     {"mouthWide", kOne, Stretch{{2.0, 7.5, 10.5}, 0.12, 0.1, 0, 7}, {"mouthStretch_L", "mouthStretch_R"}},
     {"pucker", kOne, Pucker{0.25, {0, 0, 7.5, 1.6, kLine}, 0.6, {0, 0, 3.0, 1.4, kLine}}, {"mouthPucker"}},
     {"cheekPuff", kPair, Displacement{{{0.9, {7.5, -2.2, 2.5, 2.2}, {}, kNormal}}}, {"cheekPuff_L"}},
     // Without human counterparts: the throat sac and the antennae.
     {"throatPuff", kOne, Displacement{{{1.2, {0, -3.8, 5.0, 2.0}, {}, kNormal}}}, {}},
     {"antennaBend", kPair, PartSwing{0.9}, {}}},
    {{"brow_inner_left", 4.6, 5.5},
     {"brow_middle_left", 6.0, 5.7},
     {"brow_outer_left", 7.4, 5.5},
     {"cheek_left", 8.5, -0.5},
     {"chin", 0, -3.6},
     {"forehead", 0, 5.0},
     {"jaw_left", 6.0, -3.5}}};

}  // namespace

const std::vector<AvatarSpec>& avatar_specs() {
  static const std::vector<AvatarSpec> specs = {kMoppet, kFox, kGlorp};
  return specs;
}

}  // namespace synth

std::vector<SyntheticAvatar> synthetic_avatars() {
  std::vector<SyntheticAvatar> avatars;
  for (const synth::AvatarSpec& spec : synth::avatar_specs()) avatars.push_back(synth::build_avatar(spec));
  return avatars;
}

}  // namespace retarget
