// The synthetic set as a whole and its files; the human is in synthetic_human.cpp and the
// avatars in avatar_tables.cpp (tables) and avatar_builder.cpp (the builder).
#include "synthetic/synthetic_faces.h"

#include <fmt/format.h>

#include <filesystem>

#include "core/atomic_file.h"
#include "synthetic/avatar_trim.h"

namespace retarget {

namespace fs = std::filesystem;

SyntheticSet synthetic_set(uint64_t seed) {
  SyntheticSet set;
  set.seed = seed;
  set.human = synthetic_human(seed);
  set.avatars = synthetic_avatars();
  set.avatars.push_back(with_many_parts(set.avatars[1], "bramble"));  // the fox, dressed
  return set;
}

namespace {

std::string readme(const SyntheticSet& set) {
  const FaceModel& h = set.human;
  std::string text = fmt::format(
      "Synthetic faces written by `retarget synth --seed {}`.\n"
      "Units: cm. Frame: +y up, +z towards the viewer, +x the face's own left (so `_L` / `Left`\n"
      "shapes move the +x side).\n\n"
      "human/face_model.yaml\n"
      "  A linear human face model ({}): neutral.obj ({} vertices, {} faces), {} identity modes\n"
      "  (identities/*.obj, one standard deviation each; a person is neutral + sum_i c_i (identity_i -\n"
      "  neutral), c_i ~ N(0, 1)) and {} ARKit-named expression blendshapes (expressions/*.obj, the same\n"
      "  offsets for every person), {} named landmarks and eye vertex sets. The eyelids and lips are cut:\n"
      "  upper and lower lid/lip vertices are separate, so eyes close and the mouth opens. Each eye has\n"
      "  an eyeball cap (a separate part) behind the lids and a pocket behind the lips. The seed\n"
      "  moves the mean face.\n\n"
      "avatars/<name>/rig.yaml\n"
      "  Stylized characters, each with its own topology: neutral.obj and one <controller>.obj per\n"
      "  controller (absolute positions, weights in [0, 1]), landmarks named like the human's where the\n"
      "  feature exists, eye vertex sets.\n"
      "avatars/<name>/correspondence.yaml\n"
      "  Ground truth for evaluation: the human blendshapes each controller stands for, with weights\n"
      "  (`{{}}` = no human counterpart). No human shape appears in two rows, so a human expression with\n"
      "  weights w maps to controller weights y_c = sum_h T[c][h] w_h / sum_h T[c][h]^2.\n\n",
      set.seed, h.name, h.neutral.vertex_count(), h.neutral.faces.size(), h.identities.size(), h.expressions.size(),
      h.landmarks.size());
  for (const SyntheticAvatar& a : set.avatars) {
    int counterparts = 0;
    for (const auto& row : a.correspondence) counterparts += !row.second.empty();
    text += fmt::format("  {}: {} ({} vertices, {} controllers, {} with a human counterpart)\n", a.rig.name,
                        a.description, a.rig.neutral.vertex_count(), a.rig.controller_count(), counterparts);
  }
  return text;
}

}  // namespace

void write_synthetic_set(const std::string& folder, const SyntheticSet& set) {
  const fs::path root(folder);
  write_face_model((root / "human").string(), set.human);
  std::vector<std::string> shapes;
  for (const Blendshape& b : set.human.expressions) shapes.push_back(b.name);
  for (const SyntheticAvatar& avatar : set.avatars) {
    const fs::path dir = root / "avatars" / avatar.rig.name;
    write_rig_folder(dir.string(), avatar.rig);
    std::vector<std::string> controllers;
    for (const Controller& c : avatar.rig.controllers) controllers.push_back(c.name);
    check_controller_correspondence(avatar.correspondence, controllers, shapes, avatar.rig.name);
    write_controller_correspondence(
        (dir / "correspondence.yaml").string(), avatar.correspondence, avatar.rig.name,
        "Which human blendshapes (human/face_model.yaml) each controller of this avatar stands for:\n"
        "controller: {human_blendshape: weight, ...}; {} = no human counterpart. Ground truth for\n"
        "evaluation; load with retarget::load_controller_correspondence (geometry/controller_correspondence.h).");
  }
  const std::string text = readme(set);
  write_file_atomically((root / "README.txt").string(), [&](std::ostream& out) { out << text; });
}

}  // namespace retarget
