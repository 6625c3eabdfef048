// Writing the retargeting bundle (its format and loader: bundle/bundle_format.h) from the trained
// parts: the human VAE's encoder, the translation MLP and the avatar VAE's decoder, compiled into
// one TorchScript module with the metadata and rest meshes beside it.
#pragma once

#include <torch/script.h>
#include <torch/torch.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "bundle/bundle_format.h"
#include "geometry/dr_features.h"
#include "geometry/mesh.h"
#include "geometry/rig.h"
#include "models/mesh_vae.h"
#include "models/translation_mlp.h"

namespace retarget {

// One mesh side of a bundle (the human face set or the avatar), as the trainer holds it.
struct BundleSide {
  MeshVae vae{nullptr};             // the trained VAE, any device (copied to the CPU as float32)
  torch::Tensor normaliser_min;     // [V, 9] float32, raw DR units: the Normaliser the VAE was
  torch::Tensor normaliser_max;     //   trained with (data/normaliser.h), max > min everywhere
  Mesh rest;                        // V vertices: the mesh its DR features are relative to
  DrOptions dr;                     // the options those features were computed with (threads ignored)
  std::string name;                 // the face set's or the avatar's name, non-empty
  std::string units;                // of the rest mesh ("cm", ...); may be empty when unknown
  std::vector<int> still_vertices;  // avatar: vertices its dataset never moves (data/still_vertices.h)
};

// The avatar's rig, carried so that retarget-infer can write controller weights (--weights).
struct BundleRig {
  // Controllers over the avatar rest's vertices: names, ranges and offsets go into the bundle
  // (rig.pt, the manifest's `rig`); the neutral is checked against avatar.rest (same vertex count,
  // positions within 1e-6 of its bounding-box diagonal) and not stored again.
  Rig rig;
  // Millimetres per avatar.rest unit (geometry/metrics.h, from the avatar dataset's eye
  // landmarks), for residuals in mm; 0: unknown.
  double millimetres_per_unit = 0;
};

struct BundleParts {
  BundleSide human;                     // human expression VAE: its encoder goes into the bundle
  TranslationMlp translation{nullptr};  // F: human codes [B, Lh] -> avatar codes [B, La]
  BundleSide avatar;                    // avatar VAE: its decoder goes into the bundle
  std::optional<BundleRig> rig;         // none: a bundle without a rig (no --weights)
  std::string created;                  // when it was made; empty: now (utc_timestamp())
};

// Writes the bundle into `folder` (created if needed): bundle.pt, human_rest.obj,
// avatar_rest.obj and (with a rig) rig.pt, each atomically, then manifest.yaml. An earlier
// bundle's manifest (and rig.pt) is removed first, so a failed export never leaves a manifest
// beside files it does not describe.
// Throws retarget::Error naming the part ("bundle.human.vae", "bundle.translation", "bundle.rig",
// ...) for inconsistent inputs (VAE vertex count vs. rest mesh, latent sizes vs. F, normaliser
// shapes, feature width other than 9, empty names, invalid DR options; a rig without controllers,
// with empty or repeated names, bad ranges, non-finite offsets, another neutral than the avatar
// rest, or a bad millimetres_per_unit), before anything is written, and naming the file for write
// failures.
void export_bundle(const BundleParts& parts, const std::string& folder);

// TorchScript building block in the style of export/vae_export.h (add_vae_encoder, ...):
// registers F's layers as the parameters <prefix>f1_weight/_bias, <prefix>f2_*, <prefix>f3_*,
// <prefix>g_* (detached float32 CPU copies) and returns the source of
//   <prefix>forward(self, z: Tensor) -> Tensor     z: [B, latent_in] -> [B, latent_out]
// computing TranslationMlpImpl::forward (dense skips, LeakyReLU with options.negative_slope).
std::string add_translation_mlp(torch::jit::Module& module, TranslationMlpImpl& mlp, const std::string& prefix);

}  // namespace retarget
