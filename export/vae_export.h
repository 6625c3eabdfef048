// TorchScript export of a mesh VAE (models/mesh_vae.h): two self-describing files that plain
// `torch::jit::load` (C++) and `torch.jit.load` (Python) read, with no retarget code needed.
//
//   folder/encoder.pt   __torch__.retarget.VaeEncoder
//     forward(x) -> mean                        x: [B, V, F] RAW DR features, float32
//     encode(x) -> (mean, logvar)               [B, latent] each, normalises x first
//     encode_normalised(x) -> (mean, logvar)    x already normalised
//     normalise(x), denormalise(y)              [..., V, F] <-> [..., V, F]
//   folder/decoder.pt   __torch__.retarget.VaeDecoder
//     forward(z) == decode(z) -> x              z: [B, latent] -> [B, V, F] RAW DR features
//     decode_normalised(z) -> y                 the network's tanh output, in (-1, 1)
//     normalise(x), denormalise(y)
//
// Both carry the attributes kind, name, fingerprint, version, created (str) and vertices,
// latent, features (int) (Python: `m.latent`), the buffers normaliser_min and normaliser_max
// ([V, F] float32) and the extra file `metadata.json` (read it with the `_extra_files` argument
// of torch.jit.load). The normalisation is the project's one convention (data/normaliser.h):
//   normalise(x) = 1.8 (x - min) / (max - min) - 0.9,   denormalise its inverse.
// In eval the exported modules equal MeshVae::encode / decode (no sampling) to float rounding.
//
// The graph operator L~ is stored as the buffers laplacian_indices [2, nnz] int64 and
// laplacian_values [nnz] float32; the script builds the sparse COO tensor once per call (about
// 0.1 ms for 28k entries). A sparse buffer would also survive save/load in LibTorch 1.13, but
// plain dense buffers are readable by every tool and runtime that reads TorchScript files.
#pragma once

#include <torch/script.h>
#include <torch/torch.h>

#include <cstdint>
#include <optional>
#include <string>

#include "models/mesh_vae.h"

namespace retarget {

// What an exported VAE says about itself (attributes and metadata.json of both files).
struct VaeExportMetadata {
  std::string kind;              // "avatar" or "human"
  std::string name;              // the avatar's or the face set's name, non-empty
  std::string fingerprint;       // topology fingerprint of the training mesh, non-empty
  std::string software_version;  // RETARGET_VERSION of the exporting build, non-empty
  std::string created;           // when it was exported (ISO 8601 UTC by convention); free text, may be empty
  int64_t vertices = 0;          // V of the mesh, > 0
  int64_t latent = 0;            // latent code size, > 0
  int64_t features = 9;          // per-vertex feature width F, > 0 (9 for DR features)

  void validate(const std::string& key_path = "vae_export") const;  // throws retarget::Error
};

bool operator==(const VaeExportMetadata& a, const VaeExportMetadata& b);
inline bool operator!=(const VaeExportMetadata& a, const VaeExportMetadata& b) { return !(a == b); }

// Writes folder/encoder.pt and folder/decoder.pt (see above), each atomically (core/atomic_file.h);
// creates the folder if needed and replaces earlier exports.
//   vae:            the trained model, any device; its tensors are copied to the CPU as float32.
//   normaliser_min, normaliser_max: [V, F] float32, raw DR units, max > min everywhere (the
//                   Normaliser of data/normaliser.h the VAE was trained with).
//   metadata:       validated; vertices, latent and features must match vae.options.
//   decoder_min, decoder_max: the ranges the decoder's outputs are denormalised with, when they
//                   differ from the encoder's (a human VAE's targets: Dataset::target_normaliser);
//                   undefined: normaliser_min / normaliser_max.
// Throws retarget::Error for inconsistent inputs and for files that cannot be written.
void export_vae(MeshVaeImpl& vae, const torch::Tensor& normaliser_min, const torch::Tensor& normaliser_max,
                const VaeExportMetadata& metadata, const std::string& folder, const torch::Tensor& decoder_min = {},
                const torch::Tensor& decoder_max = {});

// What the mesh in hand requires of an export; unset members are not checked.
struct ExpectedTopology {
  std::optional<int64_t> vertices;  // the mesh's vertex count V
  std::string fingerprint;          // the mesh's topology fingerprint; empty = don't check
};

struct ExportedVae {
  torch::jit::Module encoder;  // in eval mode; methods as above
  torch::jit::Module decoder;
  VaeExportMetadata metadata;  // from metadata.json (equal in both files)
};

// Loads folder/encoder.pt and folder/decoder.pt written by export_vae. Throws retarget::Error
// naming the file for: a missing file, a file that is no TorchScript module (truncated,
// garbage), a module that is not a retarget VAE export (no or unreadable metadata.json), encoder
// and decoder from different exports, and a vertex count or fingerprint other than `expected`.
ExportedVae load_exported_vae(const std::string& folder, const ExpectedTopology& expected = {});

// ---------------------------------------------------------------------------------------------
// Building blocks for TorchScript modules that contain parts of mesh VAEs: the two files above,
// and the retargeting bundle (human encoder -> translation MLP -> avatar decoder in one module).
//
// Each add_* call registers tensors (detached copies, CPU, float32) or attributes on `module`
// under names beginning with `prefix` ("" or an identifier prefix such as "human_") and returns
// TorchScript source of methods of `module`. Concatenate the sources of all parts (and the
// caller's own methods, which may call these) and pass them to module.define() once:
//
//   torch::jit::Module bundle = make_script_module("__torch__.retarget.Bundle");
//   std::string source = add_normaliser(bundle, human_min, human_max, "human_") +
//                        add_vae_encoder(bundle, human_vae, "human_") + ...;
//   source += "def forward(self, x: Tensor) -> Tensor:\n"
//             "    mean, logvar = self.human_encode_normalised(self.human_normalise(x))\n ...";
//   bundle.define(source);
//   save_module_atomically(bundle, path, {{"metadata.json", ...}});

// An empty module of the given class ("__torch__.retarget.Name") with the bool attribute
// `training` = false, which Python's torch.jit.load needs for m.training and m.eval().
torch::jit::Module make_script_module(const std::string& class_name);

// Parameters <prefix>convs_<i>_linear_weight/_bias, <prefix>encoder_hidden_*, <prefix>mean_head_*,
// <prefix>logvar_head_*, and <prefix>encoder_skip_* where the VAE has one; buffers <prefix>laplacian_indices [2, nnz]
// int64 and <prefix>laplacian_values [nnz] float32 (the coalesced COO operator) and <prefix>laplacian_offsets [V] int64
// (where each row's entries start). Defines
//   <prefix>encode_normalised(self, x: Tensor) -> Tuple[Tensor, Tensor]
//     x: [B, V, F] normalised features -> (mean, logvar), [B, latent] each.
// The graph convolutions are unrolled (vae.options: channels, order) in the [V, B, C] layout, with
// sparse products as torch.embedding_bag over the operator's rows and narrowing layers linear
// first, as ChebyshevConv's CPU kernels compute them (equal up to rounding).
std::string add_vae_encoder(torch::jit::Module& module, MeshVaeImpl& vae, const std::string& prefix);

// Parameters <prefix>decoder_hidden_*, <prefix>decoder_out_*. Defines
//   <prefix>decode_normalised(self, z: Tensor) -> Tensor
//     z: [B, latent] -> [B, V, F], tanh output in (-1, 1).
std::string add_vae_decoder(torch::jit::Module& module, MeshVaeImpl& vae, const std::string& prefix);

// Buffers <prefix>normaliser_min and <prefix>normaliser_max ([V, F] float32). Defines
//   <prefix>normalise(self, x: Tensor) -> Tensor     raw [..., V, F] -> normalised
//   <prefix>denormalise(self, y: Tensor) -> Tensor   normalised [..., V, F] -> raw
// Throws retarget::Error unless min, max are [V, F], finite, with max > min everywhere.
std::string add_normaliser(torch::jit::Module& module, const torch::Tensor& normaliser_min,
                           const torch::Tensor& normaliser_max, const std::string& prefix);

// Attributes <prefix>kind, name, fingerprint, version (= software_version), created (str) and
// <prefix>vertices, latent, features (int).
void add_metadata_attributes(torch::jit::Module& module, const VaeExportMetadata& metadata, const std::string& prefix);

// metadata.json as export_vae writes it: a JSON object with "format": "retarget-vae",
// "format_version", "part" (e.g. "encoder"), the metadata fields and, if given, the
// architecture of `vae` (informative only).
std::string vae_metadata_json(const VaeExportMetadata& metadata, const std::string& part,
                              const MeshVaeOptions* architecture = nullptr);
// The metadata in a JSON object written by vae_metadata_json (extra keys are ignored).
// Throws retarget::Error(where, ...) for invalid JSON, missing or mistyped keys, or
// invalid metadata.
VaeExportMetadata parse_vae_metadata_json(const std::string& text, const std::string& where);

// module.save(path, extra_files) through a temporary file renamed into place; throws
// retarget::Error naming the path on failure (the temporary file is removed).
void save_module_atomically(const torch::jit::Module& module, const std::string& path,
                            const torch::jit::ExtraFilesMap& extra_files = {});

}  // namespace retarget
