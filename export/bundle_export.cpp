#include "export/bundle_export.h"

#include <filesystem>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/sha256.h"
#include "core/tensor_io.h"
#include "core/timer.h"
#include "export/script_source.h"
#include "export/vae_export.h"
#include "geometry/mesh_io.h"
#include "geometry/metrics.h"
#include "geometry/topology_fingerprint.h"

namespace retarget {

namespace {

namespace fs = std::filesystem;

using script::add_linear;
using script::first_line;
using script::frozen;
using script::literal;
using script::shape_check;
using script::str;
void check_prefix(const std::string& prefix) { script::check_prefix(prefix, "bundle_export"); }

// --- checking the parts --------------------------------------------------------------------

std::string shape_of(const torch::Tensor& t) { return t.defined() ? c10::str(t.sizes()) : std::string("none"); }

void check_side(const BundleSide& side, const std::string& key) {
  if (side.vae.is_empty()) throw Error(key + ".vae", "expected a trained VAE, got none");
  const MeshVaeOptions& options = side.vae->options;
  if (options.features() != kDrWidth) {
    throw Error(key + ".vae", "expected a VAE over DR features (" + str(kDrWidth) + " per vertex), this one has " +
                                  str(options.features()));
  }
  const std::string rest = side.rest.source.empty() ? "the rest mesh" : "the rest mesh " + side.rest.source;
  if (side.rest.vertex_count() == 0 || side.rest.faces.size() == 0) {
    throw Error(key + ".rest", "expected the rest mesh the DR features are relative to, got an empty mesh");
  }
  if (options.vertices() != side.rest.vertex_count()) {
    throw Error(key + ".vae", "the VAE has " + str(options.vertices()) + " vertices but " + rest + " has " +
                                  str(side.rest.vertex_count()));
  }
  const std::vector<int64_t> shape{options.vertices(), kDrWidth};
  if (!side.normaliser_min.defined() || !side.normaliser_max.defined() ||
      side.normaliser_min.sizes() != torch::IntArrayRef(shape) ||
      side.normaliser_max.sizes() != torch::IntArrayRef(shape)) {
    throw Error(key + ".normaliser", "expected min and max of shape [" + str(options.vertices()) + ", " +
                                         str(kDrWidth) + "] for this VAE, got " + shape_of(side.normaliser_min) +
                                         " and " + shape_of(side.normaliser_max));
  }
  if (side.name.empty()) throw Error(key + ".name", "expected a name, got an empty string");
  try {
    side.dr.validate();
  } catch (const Error& e) {
    throw Error(key + ".dr", e.what());
  }
}

BundleSideMetadata side_metadata(const BundleSide& side) {
  BundleSideMetadata m;
  m.name = side.name;
  m.vertices = side.rest.vertex_count();
  m.faces = side.rest.faces.size();
  m.fingerprint = topology_fingerprint(side.rest);
  m.latent = side.vae->options.latent();
  m.units = side.units;
  m.dr = side.dr;
  m.dr.threads = 0;
  m.still_vertices.assign(side.still_vertices.begin(), side.still_vertices.end());
  return m;
}

// The rig's metadata and its offsets as [C, V, 3] float32, after checking it against the avatar.
std::pair<BundleRigMetadata, torch::Tensor> rig_part(const BundleRig& part, const Mesh& avatar_rest) {
  const Rig& rig = part.rig;
  const std::string key = "bundle.rig";
  const int64_t v = avatar_rest.vertex_count();
  if (rig.neutral.vertex_count() != v)
    throw Error(key, "the rig " + rig.source + " has " + str(rig.neutral.vertex_count()) +
                         " vertices but the avatar's rest mesh has " + str(v));
  const double diagonal = bounding_box_diagonal(avatar_rest.vertices);
  const double apart = (rig.neutral.vertices - avatar_rest.vertices).cwiseAbs().maxCoeff();
  if (!(apart <= 1e-6 * diagonal))
    throw Error(key, "the rig's neutral " + rig.source + " is not the avatar's rest mesh (vertices up to " +
                         str(apart) + " apart); its offsets would not apply to the avatar");
  BundleRigMetadata metadata;
  metadata.millimetres_per_unit = part.millimetres_per_unit;
  torch::Tensor offsets = torch::empty({rig.controller_count(), v, 3}, torch::kFloat32);
  float* out = offsets.data_ptr<float>();
  for (int k = 0; k < rig.controller_count(); ++k) {
    const Controller& c = rig.controllers[k];
    metadata.controllers.push_back({c.name, c.min, c.max});
    if (c.offset.rows() != v || !c.offset.allFinite())
      throw Error(key + ".controllers[" + str(k) + "]",
                  "the offsets of '" + c.name + "' should be " + str(v) + " x 3 finite numbers");
    for (int64_t i = 0; i < v * 3; ++i) out[k * v * 3 + i] = static_cast<float>(c.offset.data()[i]);
  }
  validate_bundle_rig(metadata, key);  // names, ranges and the scale, as load_bundle checks them
  return {std::move(metadata), std::move(offsets)};
}

}  // namespace

std::string add_translation_mlp(torch::jit::Module& module, TranslationMlpImpl& mlp, const std::string& prefix) {
  check_prefix(prefix);
  const TranslationMlpOptions& options = mlp.options;
  const std::string method = prefix + "forward";
  const std::string slope = literal(options.negative_slope());
  auto layer = [&](const torch::nn::Linear& linear, const std::string& name, const std::string& input) {
    return add_linear(module, linear, prefix + name, input);
  };
  std::ostringstream s;
  s << "def " << method << "(self, z: Tensor) -> Tensor:\n"
    << shape_check(method, "z", {-1, options.latent_in()}, "latent codes") << "    x1 = torch.leaky_relu("
    << layer(mlp.f1, "f1", "z") << ", " << slope << ")\n"
    << "    x2 = torch.leaky_relu(" << layer(mlp.f2, "f2", "x1") << ", " << slope << ")\n"
    << "    x3 = torch.leaky_relu(" << layer(mlp.f3, "f3", "torch.cat([x1, x2], 1)") << ", " << slope << ")\n"
    << "    return " << layer(mlp.g, "g", "torch.cat([x1, x2, x3], 1)") << "\n\n";
  return s.str();
}

void export_bundle(const BundleParts& parts, const std::string& folder) {
  check_side(parts.human, "bundle.human");
  check_side(parts.avatar, "bundle.avatar");
  if (parts.translation.is_empty()) throw Error("bundle.translation", "expected the translation MLP, got none");
  const TranslationMlpOptions& f = parts.translation->options;
  const int64_t human_latent = parts.human.vae->options.latent(), avatar_latent = parts.avatar.vae->options.latent();
  if (f.latent_in() != human_latent || f.latent_out() != avatar_latent) {
    throw Error("bundle.translation", "F maps " + str(f.latent_in()) + " -> " + str(f.latent_out()) +
                                          " codes but the human VAE's latent size is " + str(human_latent) +
                                          " and the avatar VAE's " + str(avatar_latent));
  }

  BundleMetadata metadata;
  metadata.software_version = RETARGET_VERSION;
  metadata.created = parts.created.empty() ? utc_timestamp() : parts.created;
  metadata.features = kDrWidth;
  metadata.human = side_metadata(parts.human);
  metadata.avatar = side_metadata(parts.avatar);
  metadata.translation_hidden = f.hidden();
  torch::Tensor rig_offsets;
  if (parts.rig) std::tie(metadata.rig, rig_offsets) = rig_part(*parts.rig, parts.avatar.rest);

  // The whole module is built (and every part checked) before anything is written.
  torch::NoGradGuard no_grad;
  torch::jit::Module bundle = make_script_module("__torch__.retarget.Bundle");
  add_bundle_attributes(bundle, metadata);

  auto normaliser = [&](const BundleSide& side, const std::string& prefix, const std::string& key) {
    try {
      return add_normaliser(bundle, side.normaliser_min, side.normaliser_max, prefix);
    } catch (const Error& e) {
      throw Error(key + ".normaliser", e.detail());
    }
  };
  const int64_t vh = metadata.human.vertices, va = metadata.avatar.vertices;
  std::string source = normaliser(parts.human, "human_", "bundle.human") +
                       add_vae_encoder(bundle, *parts.human.vae.ptr(), "human_") +
                       add_translation_mlp(bundle, *parts.translation.ptr(), "translation_") +
                       add_vae_decoder(bundle, *parts.avatar.vae.ptr(), "avatar_") +
                       normaliser(parts.avatar, "avatar_", "bundle.avatar");
  source += "def encode_human(self, x: Tensor) -> Tensor:\n" +
            shape_check("encode_human", "x", {-1, vh, kDrWidth}, "raw human DR features") +
            "    mean, logvar = self.human_encode_normalised(self.human_normalise(x))\n"
            "    return mean\n\n"
            "def translate(self, z: Tensor) -> Tensor:\n"
            "    return self.translation_forward(z)\n\n"
            "def decode_avatar(self, z: Tensor) -> Tensor:\n"
            "    return self.avatar_denormalise(self.avatar_decode_normalised(z))\n\n"
            "def forward(self, x: Tensor) -> Tensor:\n" +
            shape_check("forward", "x", {-1, vh, kDrWidth}, "raw human DR features") +
            "    y = self.decode_avatar(self.translate(self.encode_human(x)))\n" +
            shape_check("forward", "y", {-1, va, kDrWidth}, "raw avatar DR features") + "    return y\n";
  bundle.define(source);

  const fs::path dir(folder);
  std::error_code ec;
  fs::remove(dir / kBundleManifestFile, ec);
  fs::remove(dir / kBundleRigFile, ec);
  save_module_atomically(bundle, (dir / kBundleModuleFile).string(),
                         {{kBundleMetadataFile, bundle_metadata_json(metadata)}});
  write_mesh((dir / kBundleHumanRestFile).string(), parts.human.rest);
  write_mesh((dir / kBundleAvatarRestFile).string(), parts.avatar.rest);
  std::vector<std::string> files{kBundleModuleFile, kBundleHumanRestFile, kBundleAvatarRestFile};
  if (metadata.rig) {
    save_tensors((dir / kBundleRigFile).string(), {{kBundleRigOffsets, rig_offsets}});
    files.push_back(kBundleRigFile);
  }
  std::map<std::string, std::string> sha256;
  for (const std::string& file : files) sha256[file] = sha256_of_file((dir / file).string());
  write_file_atomically((dir / kBundleManifestFile).string(),
                        [&](std::ostream& out) { out << bundle_manifest_text(metadata, sha256); });
}

}  // namespace retarget
