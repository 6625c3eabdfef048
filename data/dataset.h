// Datasets of DR features on disk, the input of every trainer: an avatar dataset (random rig
// expressions) or a human dataset (people x expressions, with identity-averaged targets).
//
// One folder per dataset:
//   manifest.yaml   what it is: kind, name, software version, creation time, source (and for a
//                   glTF avatar the meshes it was made of, `gltf_meshes`), vertex
//                   count, topology fingerprint, DR options, samples, controllers or subjects
//                   and expressions, the train/test split, the seed, the file names
//   rest.obj        the rest mesh the features are relative to (the rig neutral, or the mean
//                   neutral face of a human set)
//   features.pt     tensors (torch.load gives a dict): `features` [N, V, 9] float32 raw DR
//                   features (S - I, not normalised); avatars: `weights` [N, C] float64 rig
//                   weights; humans: `subject` [N] and `expression` [N] int64 (indices into the
//                   manifest's lists), `targets` [E, V, 9] float32 (the DR features of each
//                   expression averaged over the training subjects' meshes), and for a face
//                   model `identity` [P, K] float64 (the people's identity coefficients)
//   normaliser.pt   per (vertex, channel) ranges (data/normaliser.h) of the training split's
//                   features, for humans together with the targets (also made from training
//                   subjects only): the decoder's tanh must be able to reach every target, and
//                   the DR features of a mean mesh can leave the range of the meshes' features
//                   where DR is strongly non-linear (the ICT lip corners: by up to 30%)
// Every file is written atomically and the manifest last, so a folder with a manifest is whole.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "data/normaliser.h"
#include "geometry/dr_features.h"
#include "geometry/face_model.h"
#include "geometry/mesh.h"
#include "geometry/mesh_size_limits.h"
#include "geometry/metrics.h"
#include "geometry/rig.h"

namespace retarget {

constexpr int kDatasetFormat = 1;  // manifest `format`; load_dataset refuses other values
// Avatar datasets' normaliser: the smallest range of a (vertex, channel), as a fraction of the
// channel's largest range over the vertices. A rig moves most feature dimensions only a little
// (the falloff around each controller's region); min-max normalised, each such dimension spans
// [-0.9, 0.9] like the ones that carry the expression, and the L1 loss is mostly about
// dimensions whose best guess is the rest pose. The floor narrows those in the loss's units; it
// does not by itself stop a VAE settling on the neutral face (the synthetic fox's quick VAE:
// x1.00 of the neutral answer with and without it, docs/experiments/2026-11-25-synthetic-default-end-to-end.md).
// Datasets written before this keep the ranges they were written with.
constexpr double kAvatarRangeFloor = 0.05;
// Dataset::target_normaliser: the smallest target range, as a fraction of the shared range.
constexpr double kTargetRangeFloor = 0.1;

enum class DatasetKind { avatar, human };
const char* to_string(DatasetKind kind);

struct AvatarDatasetOptions {
  std::string mesh_name;  // glTF files only: the mesh with the controllers (empty: the one with most morph targets)
  // Refuse a rig without eyes (Rig::eyes) before any work: `retarget eval retarget` measures in
  // millimetres from the eyes' distance and would stop at its end without them. false: build
  // anyway (VAE training and `eval vae` fall back to mesh units).
  bool require_eyes = true;
  int samples = 2000;                   // rig expressions, the rest pose first (the paper: 2000)
  int min_active = 1;                   // controllers active per sample, uniform in [min_active, max_active]
  int max_active = 5;                   //   each at a weight ~ U(0, 1] of its range (the paper: 1-5)
  double test_fraction = 0.1;           // share of the samples held out, chosen by a seeded shuffle; [0, 1)
  uint64_t seed = 1;                    // drives the sampling and the split
  DrOptions dr;                         // DR features against the rig neutral
  MeshSizeLimits size;                  // the rig's neutral is refused above these, before any work
  bool force = false;                   // replace the dataset files in a non-empty folder
  std::ostream* progress = &std::cerr;  // progress bars (nullptr: none)
  void validate() const;                // throws retarget::Error naming the option
};

struct HumanDatasetOptions {
  // Face model only: people drawn with identity coefficients ~ N(0, 1) (one per mode); 0: as
  // many as default_people gives for the model's identity modes.
  int people = 0;
  // Held-out subjects: test_subjects by name (face folder only), else test_people of them
  // chosen by a seeded shuffle; -1: 20% of the subjects, rounded, at least one when there are
  // two or more.
  int test_people = -1;
  std::vector<std::string> test_subjects;
  // Face folder only: the expression that is each subject's neutral face, and an optional rest
  // mesh (one topology with the folder); without one, the rest is the mean of the training
  // subjects' neutral meshes.
  std::string neutral = "neutral";
  std::string rest_mesh;
  uint64_t seed = 1;    // drives the identities and the split
  DrOptions dr;         // DR features against the rest (the mean face)
  MeshSizeLimits size;  // the face model's (or folder's) mesh is refused above these, before any work
  // Face model only: write the recipes into the dataset folder (recipes.yaml, before the
  // manifest) and record that file, e.g. when they were made here (training blends).
  bool own_recipes = false;
  bool force = false;
  std::ostream* progress = &std::cerr;
  void validate() const;
};

// What the builder did, for the command's summary.
struct DatasetSummary {
  std::string folder;
  DatasetKind kind = DatasetKind::avatar;
  int64_t samples = 0, train = 0, test = 0;
  int vertices = 0;
  int subjects = 0, expressions = 0, controllers = 0;
  std::vector<std::string> gltf_meshes;  // avatars of a glTF file: the meshes used (Dataset::gltf_meshes)
  double seconds = 0;                    // wall time of the whole build
  double features_seconds = 0;           // of which the DR features (mesh building included)
  // The range check. Training features (and human targets) span [-0.9, 0.9] by construction;
  // test features may fall outside, and beyond [-1, 1] a tanh decoder cannot reach them.
  int64_t widened = 0;                        // (vertex, channel) dimensions whose range was widened to 1e-5
  double test_min = 0, test_max = 0;          // normalised test features
  double test_outside = 0;                    // share of normalised test values with |y| > 1
  double targets_min = 0, targets_max = 0;    // humans: normalised targets (within [-0.9, 0.9])
  std::map<std::string, int64_t> file_bytes;  // file name -> size
};

// Builds an avatar dataset from a rig (a folder with rig.yaml, or a .gltf/.glb: geometry/rig.h)
// into `folder`. Throws retarget::Error for bad options or input, and when `folder` exists and
// is not empty unless options.force. Before any work: without eyes (unless
// !options.require_eyes) an error naming the rig file says how to add them; with fewer than 3
// landmarks a warning says `retarget correspond` will need --landmarks. A glTF rig's meshes
// (Rig::gltf_meshes) are recorded, so load_dataset_rig reads the same avatar back.
DatasetSummary build_avatar_dataset(const std::string& rig_path, const std::string& folder,
                                    const AvatarDatasetOptions& options = {});

// The people a face model with `modes` identity modes is sampled with when HumanDatasetOptions::
// people is 0: at least kDefaultPeople, and enough that the training people (after the 20% held
// out by default, or test_people of them when >= 0) number at least modes + ceil(modes / 3) + 1
// (the VAE trainer holds a tenth of them out for validation). Fewer training people than modes
// cannot span the ways faces differ: the encoder then maps unseen people's identity to code.
// Measured on the synthetic face model (29 modes; the linear principal encoder on 12 held-out
// people, tools in docs/experiments/2026-11-26-vae-starts.md): code ratio 0.30 with 19 training people, 0.14 with 32,
// 0.12 with 40, 0.09 with 48.
constexpr int kDefaultPeople = 24;
int64_t default_people(int64_t modes, int test_people);

// Builds a human dataset from a linear face model: options.people people x recipes meshes,
// DR features relative to the model's neutral (the mean face), split by subject. Every
// blendshape a recipe names must be in the model (else an error naming the recipe).
// `recipes_source` names the recipe file in messages and the manifest.
DatasetSummary build_human_dataset(const FaceModel& model, const std::vector<ExpressionRecipe>& recipes,
                                   const std::string& recipes_source, const std::string& folder,
                                   const HumanDatasetOptions& options = {});

// Builds a human dataset from a face folder (geometry/face_folder.h): every subject's meshes.
DatasetSummary build_face_folder_dataset(const std::string& face_folder, const std::string& folder,
                                         const HumanDatasetOptions& options = {});

// A dataset as load_dataset() returns it.
struct Dataset {
  std::string folder;
  DatasetKind kind = DatasetKind::avatar;
  std::string name;              // the rig's or the face set's name
  std::string software_version;  // RETARGET_VERSION of the build that wrote it
  std::string created;           // UTC, ISO 8601
  std::string source;            // the rig, face model or face folder it was built from
  // Avatars from a glTF file: the meshes the avatar was made of (Rig::gltf_meshes, the one with
  // the controllers first), so that the rig reloads as built; empty otherwise.
  std::vector<std::string> gltf_meshes;
  std::string recipes;      // the expression recipes (face-model datasets), else empty
  std::string units;        // of the rest mesh ("cm", ...)
  std::string fingerprint;  // topology_fingerprint(rest)
  uint64_t seed = 1;
  DrOptions dr;
  Mesh rest;                             // V vertices
  std::map<std::string, int> landmarks;  // named landmark vertices of the rest mesh (may be empty)
  EyeLandmarks eyes;                     // may be empty

  torch::Tensor features;  // [N, V, 9] float32, raw DR
  Normaliser normaliser;   // ranges of the training split (humans: with the targets)
  // The ranges of what a VAE on this dataset decodes. Avatars: `normaliser`. Humans: the ranges
  // of the identity-averaged targets alone (computed on load). The shared normaliser gives a
  // target dimension the whole span the inputs' identities cover, so where every expression
  // leaves the face still (the back of the head) a decoder had to hit a constant inside a range
  // as wide as the differences between people, and each such small miss, integrated by
  // reconstruction over the head, drifted it by millimetres; in the targets' own ranges those
  // dimensions are much narrower. Each range is kept at least kTargetRangeFloor x the shared
  // one, so that the loss, which measures errors in these units, does not magnify the
  // dimensions that barely move into the ones that matter most.
  Normaliser target_normaliser;

  std::vector<int64_t> train, test;  // sample indices, ascending; together 0..N-1

  // avatar
  std::vector<std::string> controllers;  // C
  torch::Tensor weights;                 // [N, C] float64

  // human
  std::vector<std::string> subjects;     // all subjects, in sample order
  std::vector<std::string> expressions;  // E
  std::vector<std::string> train_subjects, test_subjects;
  torch::Tensor subject;     // [N] int64 into `subjects`
  torch::Tensor expression;  // [N] int64 into `expressions`
  torch::Tensor targets;     // [E, V, 9] float32 identity-averaged targets, raw DR
  torch::Tensor identity;    // [P, K] float64 (face-model datasets only; undefined otherwise)

  int64_t sample_count() const { return features.defined() ? features.size(0) : 0; }
  int vertex_count() const { return rest.vertex_count(); }
};

// Reads a dataset folder and checks it: the manifest's format, kind and counts, the rest
// mesh against the manifest's vertex count and topology fingerprint, every tensor's shape.
// Throws retarget::Error naming the file and what is wrong. A dataset written by another
// software version loads with a warning in the log.
Dataset load_dataset(const std::string& folder);

// The controller names of an avatar dataset, read from its manifest alone (no tensors), in
// order; empty for a human dataset. Throws retarget::Error naming the folder as load_dataset does
// when it is not a dataset folder.
std::vector<std::string> dataset_controllers(const std::string& folder);
// The expression recipes file of a face-model dataset, from its manifest alone; empty for the
// others. Throws as dataset_controllers does.
std::string dataset_recipes(const std::string& folder);

// The rig an avatar dataset was built from, read as it was built: load_rig(avatar.source,
// avatar.gltf_meshes) (geometry/rig.h). Throws retarget::Error naming the source (and the
// meshes) when it does not load, and naming the dataset when its neutral's topology is not the
// dataset's (the rig changed since, or another mesh of the file was read).
Rig load_dataset_rig(const Dataset& avatar);

}  // namespace retarget
