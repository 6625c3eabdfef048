// A many-part avatar, as artists' heads come out of their tools (a game character's glTF, a
// VRoid-like face): the skin in islands cut by a texture seam, and a dozen separate pieces
// beside it. with_many_parts() dresses one of the bundled avatars (synthetic_faces.h) so:
//   - the skin cut along the face's midline (x = 0) into a left and a right island: the
//     vertices the two halves share are duplicated, as a seam leaves them (they coincide at
//     rest and move as one under every controller);
//   - upper and lower lashes on each eye: strips standing on the lid margins (rig.eyes), each
//     strip vertex moving with its margin vertex;
//   - a brow strip over each eye (through the brow landmarks), each vertex moving with the
//     skin vertex under it;
//   - an iris disc in front of each eyeball, moving with its eyeball's mean offset;
//   - upper and lower teeth (curved slabs behind the lips) and a tongue: the upper row still (on
//     the skull), the lower row and the tongue moving rigidly with the jaw (the lower lip's mean
//     offset under the controller that opens it furthest, and under no other).
// Existing pieces (eyeball caps, the mouth pocket, ears or antennae) stay. rig.parts names
// what a glTF loader finds by mesh name: the eyeballs (eye_left, eye_right), the teeth (one
// part holding both rows, as one mesh holds them in many exports) and the tongue; lashes,
// brows, irises and the rest are unnamed pieces. Landmarks and eye sets keep their vertices.
// Units and frame: the base avatar's (cm, +y up, +z towards the viewer, +x its left).
#pragma once

#include <string>

#include "synthetic/synthetic_faces.h"

namespace retarget {

// The base avatar dressed as above, renamed `name`; the correspondence is the base's.
// Deterministic. Throws retarget::Error when the base lacks what the pieces hang from (eye
// sets, brow or lip landmarks, a controller that opens the jaw).
SyntheticAvatar with_many_parts(const SyntheticAvatar& base, const std::string& name);

}  // namespace retarget
