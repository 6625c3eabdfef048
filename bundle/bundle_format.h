// The retargeting bundle's format: everything retarget-infer needs to carry human expressions onto one
// avatar, in one folder that describes itself and that load_bundle() checks before anything runs.
//
//   folder/manifest.yaml     what the bundle is (below); written last, so a folder with a manifest
//                            is whole
//   folder/bundle.pt         ONE TorchScript module __torch__.retarget.Bundle (plain torch::jit::load
//                            and Python's torch.jit.load read it, no retarget code needed):
//     forward(x) -> y            x: [B, Vh, 9] RAW human DR features (against human_rest.obj),
//                                y: [B, Va, 9] RAW avatar DR features (against avatar_rest.obj),
//                                float32; = decode_avatar(translate(encode_human(x)))
//     encode_human(x) -> [B, Lh]       the human VAE's code means (normalises x first; no sampling)
//     translate(z) -> [B, La]          the translation MLP F
//     decode_avatar(z) -> [B, Va, 9]   the avatar VAE's decoder, denormalised
//     human_normalise(x), human_denormalise(y), avatar_normalise(x), avatar_denormalise(y)
//                                the project's one normalisation (bundle/normalisation.h)
//     attributes: format, software_version, created (str), format_version, features (int) and per
//     side (prefix human_ / avatar_): name, fingerprint, units, dr_weighting (str), vertices, faces,
//     latent (int), dr_normal_term (bool), dr_normal_weight (float); translation_hidden (int);
//     extra file metadata.json (the manifest's content as JSON).
//   folder/human_rest.obj    the mesh the human DR features are relative to (the mean neutral face)
//   folder/avatar_rest.obj   the avatar's neutral: the reference of its DR features, and the
//                            topology (faces) every output mesh is written with
//   folder/rig.pt            (optional, format_version 3) the avatar's rig: core/tensor_io.h's dict
//                            {"offsets": [C, Va, 3] float32, target minus neutral per controller, in
//                            avatar_rest.obj's units and frame}; its neutral is avatar_rest.obj.
//                            What retarget-infer --weights solves the controller weights with.
//
// manifest.yaml:
//   format: retarget-bundle
//   format_version: 3
//   software_version: 0.1.0
//   created: 2026-11-21T09:30:00Z
//   features: 9
//   human:  {name: ict, vertices: 11248, faces: 11144, fingerprint: 0123456789abcdef, latent: 25,
//            units: cm, dr: {weighting: cotangent, normal_term: true, normal_weight: 0.0001}}
//   avatar: {name: lapin, ... the same keys}
//   translation: {hidden: 100}
//   rig:                                      # optional (format_version 3); absent: no rig
//     millimetres_per_unit: 16.1              # of avatar_rest.obj (eye landmarks); 0: unknown
//     controllers:                            # in rig.pt's order
//       - {name: jawOpen, range: [0, 1]}
//   files: {module: bundle.pt, human_rest: human_rest.obj, avatar_rest: avatar_rest.obj, rig: rig.pt}
//   sha256: {bundle.pt: <64 hex digits>, human_rest.obj: ..., avatar_rest.obj: ..., rig.pt: ...}
//
// sha256 (format_version 2): the checksum of every file the manifest names, so that a damaged or
// edited bundle.pt (whose zip entries LibTorch does not verify) or rest mesh is refused at load,
// naming the file, instead of running to nonsense. Version 1 bundles have none and load with a
// warning. The rig (format_version 3) is optional: bundles of versions 1 and 2, and bundles
// exported from an avatar dataset whose rig no longer loads, have none.
#pragma once

#include <torch/script.h>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "geometry/dr_features.h"
#include "geometry/mesh.h"
#include "geometry/rig.h"

// Written by export/bundle_export.h (export_bundle); read here without any of models/' training
// code, so that the lean runtime (infer/) needs only this library.
namespace retarget {

constexpr const char* kBundleFormat = "retarget-bundle";
// load_bundle refuses newer versions; 2: sha256; 3: the optional rig (rig.pt)
constexpr int64_t kBundleFormatVersion = 3;
constexpr const char* kBundleManifestFile = "manifest.yaml";
constexpr const char* kBundleModuleFile = "bundle.pt";
constexpr const char* kBundleHumanRestFile = "human_rest.obj";
constexpr const char* kBundleAvatarRestFile = "avatar_rest.obj";
constexpr const char* kBundleRigFile = "rig.pt";
constexpr const char* kBundleRigOffsets = "offsets";          // the tensor's name in rig.pt
constexpr const char* kBundleMetadataFile = "metadata.json";  // inside bundle.pt

// What a bundle says about one of its sides (manifest.yaml, metadata.json, module attributes).
struct BundleSideMetadata {
  std::string name;
  int64_t vertices = 0;     // V of the rest mesh (and of the VAE)
  int64_t faces = 0;        // polygons of the rest mesh, as in its file
  std::string fingerprint;  // topology_fingerprint(rest)
  int64_t latent = 0;       // code size of the VAE
  std::string units;        // may be empty
  DrOptions dr;             // weighting, normal_term, normal_weight (threads is not stored)
  // Vertices the side's dataset never moves, held at their rest positions when its meshes are
  // reconstructed (ReconstructionOptions::anchors); ascending, in [0, vertices). Avatar side
  // only; empty: none (bundles written before they existed). manifest key `still_vertices`.
  std::vector<int64_t> still_vertices;
};

// One controller of the avatar's rig, as the bundle names it.
struct BundleController {
  std::string name;         // non-empty, unique in the rig
  double min = 0, max = 1;  // weight range, finite, min < max
};

// What a bundle says about the avatar's rig (manifest key `rig`); the offsets are in rig.pt.
struct BundleRigMetadata {
  std::vector<BundleController> controllers;  // >= 1, in rig.pt's order
  // Millimetres per avatar_rest.obj unit (geometry/metrics.h: millimetres_per_unit from the
  // avatar dataset's eye landmarks), for residuals in mm; 0: unknown (no eye landmarks).
  double millimetres_per_unit = 0;
};

// Throws retarget::Error(where + ".controllers[i].name" / ".range" / ".millimetres_per_unit", ...)
// for no controllers, an empty or repeated name, a range that is not finite with min < max, or a
// scale that is negative or not finite.
void validate_bundle_rig(const BundleRigMetadata& rig, const std::string& where);

struct BundleMetadata {
  std::string format = kBundleFormat;
  int64_t format_version = kBundleFormatVersion;
  std::string software_version;  // RETARGET_VERSION of the exporting build
  std::string created;           // ISO 8601 UTC by convention
  int64_t features = 9;          // per-vertex feature width (DR: 9)
  BundleSideMetadata human, avatar;
  int64_t translation_hidden = 0;        // width of F's hidden layers (informative)
  std::optional<BundleRigMetadata> rig;  // none: the bundle carries no rig (rig.pt absent)
};

bool operator==(const BundleMetadata& a, const BundleMetadata& b);
inline bool operator!=(const BundleMetadata& a, const BundleMetadata& b) { return !(a == b); }

// The metadata as bundle.pt's attributes (format, format_version, software_version, created,
// features, translation_hidden and per side human_* / avatar_*), and as manifest.yaml's text.
// sha256: file name -> SHA-256 (core/sha256.h) of the files in the manifest's `files`; written as
// the manifest's `sha256` map (omitted when empty). `files` lists rig.pt when metadata.rig is set.
void add_bundle_attributes(torch::jit::Module& module, const BundleMetadata& metadata);
std::string bundle_manifest_text(const BundleMetadata& metadata, const std::map<std::string, std::string>& sha256 = {});
// manifest.yaml's text back, with every check load_bundle() makes on the manifest (format,
// format_version, keys and their types, the sha256 map's form); `name` stands for the file in
// messages ("name:line: key path"). For tests and the fuzzer; load_bundle() reads the file itself.
BundleMetadata parse_bundle_manifest(const std::string& text, const std::string& name);

struct LoadedBundle {
  std::string folder;
  torch::jit::Module module;  // bundle.pt, in eval mode; methods as above
  BundleMetadata metadata;    // from manifest.yaml (equal to bundle.pt's metadata.json)
  Mesh human_rest;            // metadata.human.vertices vertices, source = its path
  Mesh avatar_rest;           // metadata.avatar.vertices vertices
  // The avatar's rig when the bundle carries one (metadata.rig): neutral = avatar_rest,
  // controllers named and ranged as metadata.rig says with rig.pt's offsets, name and units the
  // avatar's, source = rig.pt's path; no landmarks or eyes.
  std::optional<Rig> rig;
};

// Loads and checks a bundle written by export_bundle. Throws retarget::Error naming the file
// for: no such folder; a missing file; a manifest that is not valid YAML, not a bundle manifest
// (format), of a newer format_version, or with a missing or mistyped key ("file:line: key path");
// a file whose SHA-256 differs from the manifest's, or (format_version >= 2) has none there;
// a bundle.pt that is no TorchScript module, has no metadata.json, lacks a method, or comes from
// another export than the manifest; rest meshes that cannot be read or whose vertex count, face
// count or topology fingerprint differs from the manifest's; a rig.pt (when the manifest has a
// rig) that is missing, unreadable, without "offsets", of another shape than [C, Va, 3] or with
// values that are not finite.
LoadedBundle load_bundle(const std::string& folder);

// The manifest's content as the JSON object stored as bundle.pt's metadata.json, and back.
// parse_bundle_metadata_json throws retarget::Error(where, ...) for invalid JSON, another format,
// a newer format_version, and missing or mistyped keys.
std::string bundle_metadata_json(const BundleMetadata& metadata);
BundleMetadata parse_bundle_metadata_json(const std::string& text, const std::string& where);

}  // namespace retarget
