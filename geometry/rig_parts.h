// Avatar parts (Rig::parts) by name: which glTF mesh names mean an eye, the teeth or the
// tongue, and the eyes (Rig::eyes) an avatar's eye parts give. Used by the glTF and rig.yaml
// loaders (geometry/rig.h).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "geometry/rig.h"

namespace retarget {

// The name split into lower-case words at '_', '.', '-', ':', spaces and digits and where a
// lower-case letter is followed by an upper-case one: "EyeLeft" -> {eye, left},
// "Wolf3D_Teeth" -> {wolf, d, teeth}, "Eye.R" -> {eye, r}.
std::vector<std::string> name_words(const std::string& name);

// The kind a name says a part is (case-insensitive, by words): eye/eyes/eyeball/eyeballs with
// left/l or right/r -> eye_left/eye_right (unless another word is lash(es), brow(s), lid(s),
// occlusion, tear(line), shadow, wet or highlight); teeth/tooth -> teeth; tongue -> tongue;
// anything else (an eye without a side too) -> nullopt.
std::optional<PartKind> part_kind_from_name(const std::string& name);

// "eye_left", "eye_right", "teeth", "tongue" or "other" -> the kind; nullopt otherwise.
std::optional<PartKind> parse_part_kind(const std::string& text);

// When rig.eyes is empty and rig.parts has eye_left and eye_right parts: rig.eyes.left/right =
// the vertices of all eye_left/eye_right parts (their centroids are the eye centres). Logs a
// warning naming rig.source when the left eye's centroid has the smaller x (the glTF
// convention, facing +Z, puts the character's left eye at larger x), keeping the names.
void eyes_from_parts(Rig& rig);

}  // namespace retarget
