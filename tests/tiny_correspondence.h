// A tiny human dataset (face model with recipes), a tiny avatar dataset, a VAE trained on it for
// a few epochs and the rig's controller table: the inputs of the correspondence and annotation
// tests, built once per test process (about a second).
#pragma once

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "data/dataset.h"
#include "geometry/controller_correspondence.h"
#include "geometry/face_model.h"
#include "geometry/rig.h"
#include "test_support.h"
#include "tiny_data.h"
#include "train/vae_config.h"
#include "train/vae_trainer.h"

namespace retarget::test {

struct TinyCorrespondenceData {
  std::string human;         // human dataset: 8 people x recipes neutral, A, AB, C (36 vertices)
  std::string avatar;        // avatar dataset: 60 samples of tiny_rig(7) (64 vertices)
  std::string run;           // the avatar VAE run (latent 4)
  std::string table;         // correspondence.yaml: ctrl0 = a, ctrl1 = b, ctrl2 = c, ctrl3 = nothing
  std::string other_avatar;  // another topology: 20 samples of tiny_rig(6)
};

// Builds the data into `dir` (about a second).
inline TinyCorrespondenceData build_tiny_correspondence_data(const std::filesystem::path& dir) {
  TinyCorrespondenceData d;
  // Both meshes cover [0, 2]^2 with the same bump; their corners are the shared landmarks.
  FaceModel model = tiny_face_model();
  model.landmarks = {{"corner00", 0}, {"corner10", 5}, {"corner01", 30}, {"corner11", 35}};
  write_face_model((dir / "face").string(), model);
  const std::string recipes = (dir / "recipes.yaml").string();
  std::ofstream(recipes) << "recipes:\n"
                            "  - {name: neutral, weights: {}}\n"
                            "  - {name: A, weights: {a: 1.0}}\n"
                            "  - {name: AB, weights: {a: 0.5, b: 1.0}}\n"
                            "  - {name: C, weights: {c: 1.0}}\n";
  HumanDatasetOptions h;
  h.people = 8;
  h.test_people = 2;
  h.seed = 4;
  h.progress = nullptr;
  d.human = (dir / "human").string();
  build_human_dataset(load_face_model((dir / "face").string()), load_expression_recipes(recipes), recipes, d.human, h);

  Rig rig = tiny_rig(7);
  rig.landmarks = {{"corner00", 0}, {"corner10", 7}, {"corner01", 56}, {"corner11", 63}};
  write_rig_folder((dir / "rig").string(), rig);
  AvatarDatasetOptions a;
  a.samples = 60;
  a.test_fraction = 0.2;
  a.seed = 2;
  a.progress = nullptr;
  d.avatar = (dir / "avatar").string();
  build_avatar_dataset((dir / "rig").string(), d.avatar, a);
  d.table = (dir / "correspondence.yaml").string();
  write_controller_correspondence(
      d.table, {{"ctrl0", {{"a", 1.0}}}, {"ctrl1", {{"b", 1.0}}}, {"ctrl2", {{"c", 1.0}}}, {"ctrl3", {}}}, "blob");

  Rig other = tiny_rig(6);
  other.landmarks = {{"corner00", 0}, {"corner10", 6}, {"corner01", 42}, {"corner11", 48}};
  write_rig_folder((dir / "other_rig").string(), other);
  a.samples = 20;
  d.other_avatar = (dir / "other_avatar").string();
  build_avatar_dataset((dir / "other_rig").string(), d.other_avatar, a);

  d.run = (dir / "run").string();
  const std::string config =
      "task: vae\n"
      "data: {dataset: " +
      d.avatar +
      ", validation_fraction: 0.2}\n"
      "model: {channels: [9, 8, 4, 1], hidden: 32, latent: 4, order: 2}\n"
      "loss: {kl_weight: 1.0e-4}\n"
      "optimiser: {lr: 1.0e-2}\n"
      "schedule: {decay: 0.6, every: 3}\n"
      "training: {epochs: 3, batch_size: 10, checkpoint_every: 1, seed: 7, threads: 1}\n"
      "output: " +
      d.run + "\n";
  VaeTrainOptions t;
  t.progress = nullptr;
  train_vae(read_vae_train_config(ConfigNode::parse(config, "tiny_avatar_vae.yaml")), t);
  return d;
}

// Built once per test process.
inline const TinyCorrespondenceData& tiny_correspondence_data() {
  static const TinyCorrespondenceData data =
      build_tiny_correspondence_data(process_scratch_dir("tiny_correspondence_data"));
  return data;
}

}  // namespace retarget::test
