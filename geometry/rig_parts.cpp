#include "geometry/rig_parts.h"

#include <algorithm>
#include <cctype>
#include <set>

#include "core/log.h"

namespace retarget {

const char* to_string(PartKind kind) {
  switch (kind) {
    case PartKind::eye_left:
      return "eye_left";
    case PartKind::eye_right:
      return "eye_right";
    case PartKind::teeth:
      return "teeth";
    case PartKind::tongue:
      return "tongue";
    case PartKind::other:
      break;
  }
  return "other";
}

std::optional<PartKind> parse_part_kind(const std::string& text) {
  for (PartKind kind : {PartKind::eye_left, PartKind::eye_right, PartKind::teeth, PartKind::tongue, PartKind::other})
    if (text == to_string(kind)) return kind;
  return std::nullopt;
}

std::vector<std::string> name_words(const std::string& name) {
  std::vector<std::string> words;
  std::string word;
  auto flush = [&] {
    if (!word.empty()) words.push_back(word);
    word.clear();
  };
  for (size_t k = 0; k < name.size(); ++k) {
    const unsigned char ch = static_cast<unsigned char>(name[k]);
    if (!std::isalpha(ch)) {
      flush();
      continue;
    }
    if (std::isupper(ch) && k > 0 && std::islower(static_cast<unsigned char>(name[k - 1]))) flush();
    word += static_cast<char>(std::tolower(ch));
  }
  flush();
  return words;
}

std::optional<PartKind> part_kind_from_name(const std::string& name) {
  const std::vector<std::string> words = name_words(name);
  const std::set<std::string> set(words.begin(), words.end());
  auto any = [&set](std::initializer_list<const char*> options) {
    return std::any_of(options.begin(), options.end(), [&set](const char* w) { return set.count(w) > 0; });
  };
  if (any({"tongue"})) return PartKind::tongue;
  if (any({"teeth", "tooth"})) return PartKind::teeth;
  if (!any({"eye", "eyes", "eyeball", "eyeballs"})) return std::nullopt;
  if (any({"lash", "lashes", "eyelash", "eyelashes", "brow", "brows", "eyebrow", "eyebrows", "lid", "lids", "eyelid",
           "eyelids", "occlusion", "tear", "tearline", "shadow", "wet", "highlight"}))
    return std::nullopt;
  const bool left = any({"left", "l"}), right = any({"right", "r"});
  if (left == right) return std::nullopt;  // no side, or both
  return left ? PartKind::eye_left : PartKind::eye_right;
}

void eyes_from_parts(Rig& rig) {
  if (!rig.eyes.left.empty() || !rig.eyes.right.empty()) return;
  EyeLandmarks eyes;
  for (const RigPart& part : rig.parts) {
    if (part.kind == PartKind::eye_left) eyes.left.insert(eyes.left.end(), part.vertices.begin(), part.vertices.end());
    if (part.kind == PartKind::eye_right)
      eyes.right.insert(eyes.right.end(), part.vertices.begin(), part.vertices.end());
  }
  if (eyes.left.empty() || eyes.right.empty()) return;
  auto mean_x = [&rig](const std::vector<int>& set) {
    double sum = 0;
    for (int v : set) sum += rig.neutral.vertices(v, 0);
    return sum / static_cast<double>(set.size());
  };
  if (mean_x(eyes.left) < mean_x(eyes.right))
    log::warn(
        "{}: the left eye part's centre (x = {:.4g}) is at smaller x than the right one's ({:.4g}); glTF avatars face "
        "+Z, so the character's left eye is usually at larger x: the parts may be named from the viewer's side "
        "(kept as named; only the eyes' distance is used for the scale)",
        rig.source, mean_x(eyes.left), mean_x(eyes.right));
  rig.eyes = std::move(eyes);
}

}  // namespace retarget
