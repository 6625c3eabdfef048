// Where `retarget pipeline` puts everything in the run folder, and which rig, face model and
// controller table a recipe resolves to. Every stage reads its paths from here.
//
//   RUN/recipe.yaml            the merged recipe of the last run
//   RUN/pipeline/              each stage's manifest and log (pipeline/pipeline_runner.h)
//   RUN/synth/                 retarget synth (synthetic face model and avatars), when used
//   RUN/avatar/<name>/         avatar init: the rig with proposed landmarks, eyes and parts
//   RUN/datasets/{avatar,human}/
//   RUN/pictures/, RUN/geometry/   extras
//   RUN/runs/{avatar_vae,human_vae}/   the VAEs with evaluation and TorchScript export
//   RUN/runs/cyclegan/         the CycleGAN+LFD baseline (between the VAEs) and its bundle/
//   RUN/proposed.yaml          the controller table `avatar meaning` proposes (the prior)
//   RUN/test_faces/            unseen people's references and blends
//   RUN/<method.folder>/       rounds/, translation/, bundle*/, rig_head.yaml, meshes, evaluation/
#pragma once

#include <string>

#include "pipeline/recipe.h"

namespace retarget {

// folder/name
std::string path_in(const std::string& folder, const std::string& name);

struct RunLayout {
  std::string run;
  std::string synth;       // RUN/synth
  std::string rig_source;  // the rig as the recipe gives it (resolved for synthetic/<name>)
  std::string rig;         // the rig the datasets are built from (avatar init's folder, or rig_source)
  std::string table;       // the controller table annotators read and the evaluation scores against
  std::string face_model;  // the face model YAML (resolved for synthetic)
  std::string avatar_dataset, human_dataset;
  std::string avatar_vae, human_vae;
  std::string cyclegan;                                                        // RUN/runs/cyclegan
  std::string cyclegan_bundle() const { return path_in(cyclegan, "bundle"); }  // its retargeting bundle
  std::string proposed;
  std::string test_faces;
  std::string method;                   // RUN/<method.folder>
  std::string round(int number) const;  // METHOD/rounds/<number>
};

RunLayout run_layout(const Recipe& recipe, const std::string& run);

}  // namespace retarget
