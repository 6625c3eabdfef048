#include "export/vae_export.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <utility>
#include <vector>

#include "bundle/normalisation.h"
#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "core/json_fields.h"
#include "export/script_source.h"

namespace retarget {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr double kSlope = kMeshVaeSlope;
constexpr double kBound = kNormalisedBound;
constexpr const char* kFormat = "retarget-vae";
constexpr int64_t kFormatVersion = 1;
constexpr const char* kEncoderFile = "encoder.pt";
constexpr const char* kDecoderFile = "decoder.pt";
constexpr const char* kMetadataFile = "metadata.json";

using script::add_linear;
using script::first_line;
using script::frozen;
using script::literal;
using script::shape_check;
using script::str;
void check_vae_prefix(const std::string& prefix) { script::check_prefix(prefix, "vae_export"); }

void require_metadata_matches(const VaeExportMetadata& metadata, const MeshVaeOptions& options) {
  auto check = [](int64_t in_metadata, int64_t in_model, const std::string& field) {
    if (in_metadata != in_model) {
      throw Error("vae_export." + field, "the metadata says " + str(in_metadata) + " but the VAE has " + str(in_model));
    }
  };
  check(metadata.vertices, options.vertices(), "vertices");
  check(metadata.latent, options.latent(), "latent");
  check(metadata.features, options.features(), "features");
}

// --- loading ------------------------------------------------------------------------------

struct LoadedPart {
  torch::jit::Module module;
  json document;  // metadata.json
  VaeExportMetadata metadata;
};

LoadedPart load_part(const fs::path& path, const std::string& part, const std::vector<std::string>& methods) {
  const std::string file = path.string();
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    throw Error(file, "missing file (an exported VAE folder holds encoder.pt and decoder.pt, written by export_vae)");
  }
  torch::jit::ExtraFilesMap extra{{kMetadataFile, ""}};
  LoadedPart loaded;
  try {
    loaded.module = torch::jit::load(file, torch::Device(torch::kCPU), extra);
  } catch (const std::exception& e) {
    throw Error(file, "cannot be read as a TorchScript module (truncated, or not a .pt file?): " + first_line(e));
  }
  const std::string& text = extra[kMetadataFile];
  if (text.empty()) throw Error(file, "not a retarget VAE export: it has no metadata.json");
  loaded.metadata = parse_vae_metadata_json(text, file);
  const JsonFields fields{file, kMetadataFile};
  loaded.document = fields.parse(text);
  const std::string found_part = fields.get<std::string>(loaded.document, "part");
  if (found_part != part) {
    throw Error(file, "holds the " + found_part + " of an exported VAE, expected the " + part);
  }
  for (const std::string& method : methods) {
    if (!loaded.module.find_method(method)) {
      throw Error(file, "not a retarget VAE " + part + ": it has no method " + method + "()");
    }
  }
  loaded.module.eval();
  return loaded;
}

// Throws unless the two metadata documents agree on every key but "part".
void require_same_export(const LoadedPart& encoder, const LoadedPart& decoder, const std::string& decoder_file) {
  json a = encoder.document, b = decoder.document;
  a.erase("part");
  b.erase("part");
  if (a == b) return;
  std::string key;
  for (const auto& item : a.items()) {
    if (!b.contains(item.key()) || b[item.key()] != item.value()) {
      key = item.key();
      break;
    }
  }
  if (key.empty()) {
    for (const auto& item : b.items()) {
      if (!a.contains(item.key())) key = item.key();
    }
  }
  auto shown = [&key](const json& document) { return document.contains(key) ? document[key].dump() : "missing"; };
  throw Error(decoder_file, "does not belong with encoder.pt (they come from different exports): \"" + key + "\" is " +
                                shown(b) + " here and " + shown(a) + " in encoder.pt");
}

}  // namespace

void VaeExportMetadata::validate(const std::string& key_path) const {
  require(kind == "avatar" || kind == "human", key_path + ".kind",
          "expected \"avatar\" or \"human\", got \"" + kind + "\"");
  require(!name.empty(), key_path + ".name", "expected a name, got an empty string");
  require(!fingerprint.empty(), key_path + ".fingerprint", "expected the topology fingerprint, got an empty string");
  require(!software_version.empty(), key_path + ".software_version", "expected a version, got an empty string");
  require_positive(static_cast<double>(vertices), key_path + ".vertices");
  require_positive(static_cast<double>(latent), key_path + ".latent");
  require_positive(static_cast<double>(features), key_path + ".features");
}

bool operator==(const VaeExportMetadata& a, const VaeExportMetadata& b) {
  return a.kind == b.kind && a.name == b.name && a.fingerprint == b.fingerprint &&
         a.software_version == b.software_version && a.created == b.created && a.vertices == b.vertices &&
         a.latent == b.latent && a.features == b.features;
}

torch::jit::Module make_script_module(const std::string& class_name) {
  torch::jit::Module module{c10::QualifiedName(class_name)};
  module.register_attribute("training", c10::BoolType::get(), false);
  return module;
}

std::string add_vae_encoder(torch::jit::Module& module, MeshVaeImpl& vae, const std::string& prefix) {
  check_vae_prefix(prefix);
  const MeshVaeOptions& options = vae.options;
  const std::string v = str(options.vertices());
  const std::string method = prefix + "encode_normalised";
  // Every graph conv holds the same operator (MeshVaeImpl::reset); the first conv's buffer is
  // the one a loaded checkpoint fills.
  torch::Tensor laplacian = vae.convs[0]->as<ChebyshevConvImpl>()->laplacian.detach().to(torch::kCPU);
  laplacian = (laplacian.is_sparse() ? laplacian : laplacian.to_sparse()).coalesce();
  const torch::Tensor indices = laplacian.indices().to(torch::kInt64).contiguous().clone();
  // Coalesced COO is sorted by (row, column): row i's entries start at offsets[i] (a row without
  // entries is an empty bag, which sums to zero).
  const torch::Tensor counts = torch::bincount(indices[0], {}, options.vertices());
  const torch::Tensor offsets = (counts.cumsum(0) - counts).to(torch::kInt64).contiguous();
  module.register_buffer(prefix + "laplacian_indices", indices);
  module.register_buffer(prefix + "laplacian_values", frozen(laplacian.values()));
  module.register_buffer(prefix + "laplacian_offsets", offsets);

  // Signals live vertex-major, [V, B, C] (contiguous, so also [V, B * C]): one sparse product
  // covers the whole batch and the Linear layers see contiguous rows; nothing is permuted between
  // layers. A sparse product L~ s is torch.embedding_bag over s viewed [V, B * C] with the rows of
  // L~ as bags (columns as indices, entries as per-sample weights, mode sum): compressed rows
  // summed in column order, the same sums as torch.mm on the coalesced COO operator and
  // ChebyshevConv's own kernel, and several times faster than torch.mm's COO product on CPU.
  // 2 L~ uses the doubled entries (exact: doubling commutes with rounding).
  int64_t max_order = 0;
  for (size_t i = 0; i < vae.convs->size(); ++i) {
    max_order = std::max(max_order, vae.convs[i]->as<ChebyshevConvImpl>()->options.order());
  }
  std::ostringstream s;
  s << "def " << method << "(self, x: Tensor) -> Tuple[Tensor, Tensor]:\n"
    << shape_check(method, "x", {-1, options.vertices(), options.features()}, "normalised features")
    << "    columns = self." << prefix << "laplacian_indices[1]\n"
    << "    offsets = self." << prefix << "laplacian_offsets\n"
    << "    values = self." << prefix << "laplacian_values\n";
  if (max_order >= 2) s << "    values2 = 2.0 * values\n";
  s << "    batch = x.size(0)\n"
    << "    h = x.transpose(0, 1).contiguous()  # [V, B, F]\n";
  // scale * L~ s for s [V, B, c] contiguous -> [V, B, c].
  auto product = [&](const std::string& signal, int64_t channels, bool doubled) {
    return "torch.embedding_bag(" + signal + ".view([" + v + ", batch * " + str(channels) +
           "]), columns, offsets, False, 0, False, " + (doubled ? "values2" : "values") + ")[0].view([" + v +
           ", batch, " + str(channels) + "])";
  };
  // The graph convolutions unrolled, as ChebyshevConvImpl::forward computes them with its sparse
  // kernels: terms first ([T0 h | T1 h | ...] W^T) unless the conv narrows (out < in), then the
  // Linear first and Clenshaw's recurrence on the narrower signal u = [u_0 | u_1 | ...] = h W_k^T:
  // b_K = u_K, b_k = u_k + 2 L~ b_(k+1) - b_(k+2), y = u_0 + L~ b_1 - b_2.
  for (size_t i = 0; i < vae.convs->size(); ++i) {
    const ChebyshevConvImpl& conv = *vae.convs[i]->as<ChebyshevConvImpl>();
    const int64_t in = conv.options.in(), out = conv.options.out(), order = conv.options.order();
    const std::string name = prefix + "convs_" + str(static_cast<int64_t>(i)) + "_linear";
    s << "    # graph conv " << i << ": " << in << " -> " << out << " channels, terms T0..T" << order << "\n";
    if (order == 0) {
      s << "    h = " << add_linear(module, conv.linear, name, "h") << "\n";
    } else if (out >= in) {
      s << "    t0 = h\n"
        << "    t1 = " << product("t0", in, false) << "\n";
      for (int64_t k = 2; k <= order; ++k) {
        s << "    t" << k << " = " << product("t" + str(k - 1), in, true) << " - t" << k - 2 << "\n";
      }
      std::string terms = "torch.cat([";
      for (int64_t k = 0; k <= order; ++k) terms += (k ? ", t" : "t") + str(k);
      s << "    h = " << add_linear(module, conv.linear, name, terms + "], 2)") << "\n";
    } else {
      // W [out, (K + 1) in] (term-major) -> [W_0; W_1; ...] [(K + 1) out, in]; the bias joins u_0.
      const std::string k1 = str(order + 1);
      add_linear(module, conv.linear, name, "h");
      const std::string w = "self." + name + "_weight";
      s << "    w = " << w << ".view([" << out << ", " << k1 << ", " << in << "]).transpose(0, 1).reshape([" << k1
        << " * " << out << ", " << in << "])\n";
      std::string bias = "None";
      if (conv.linear->bias.defined()) {
        s << "    bias = torch.cat([self." << name << "_bias, torch.zeros([" << order * out << "], dtype=" << w
          << ".dtype)])\n";
        bias = "bias";
      }
      s << "    u = torch.linear(h, w, " << bias << ")  # [V, B, (K + 1) out]\n";
      auto u = [&](int64_t k) { return "u[:, :, " + str(k * out) + ":" + str((k + 1) * out) + "]"; };
      s << "    b" << order << " = " << u(order) << ".contiguous()\n";
      for (int64_t k = order - 1; k >= 0; --k) {
        s << "    b" << k << " = " << product("b" + str(k + 1), out, k > 0) << " + " << u(k);
        if (k + 2 <= order) s << " - b" << k + 2;
        s << "\n";
      }
      s << "    h = b0\n";
    }
    const bool last = i + 1 == vae.convs->size();
    s << "    h = " << (last ? "torch.tanh(h)" : "torch.leaky_relu(h, " + literal(kSlope) + ")") << "\n";
  }
  // [V, B, C] -> [B, V * C], vertex-major per sample as MeshVaeImpl::encode flattens [B, V, C].
  s << "    h = h.transpose(0, 1).reshape([batch, " << options.vertices() * options.channels().back() << "])\n"
    << "    h = torch.leaky_relu(" << add_linear(module, vae.encoder_hidden, prefix + "encoder_hidden", "h") << ", "
    << literal(kSlope) << ")\n"
    << "    mean = " << add_linear(module, vae.mean_head, prefix + "mean_head", "h") << "\n";
  if (!vae.encoder_skip.is_empty())  // the linear path from the input straight to the code's mean
    s << "    mean = mean + "
      << add_linear(module, vae.encoder_skip, prefix + "encoder_skip",
                    "x.reshape([batch, " + str(options.vertices() * options.features()) + "])")
      << "\n";
  s << "    return mean, " << add_linear(module, vae.logvar_head, prefix + "logvar_head", "h") << "\n\n";
  return s.str();
}

std::string add_vae_decoder(torch::jit::Module& module, MeshVaeImpl& vae, const std::string& prefix) {
  check_vae_prefix(prefix);
  const MeshVaeOptions& options = vae.options;
  const std::string method = prefix + "decode_normalised";
  std::ostringstream s;
  s << "def " << method << "(self, z: Tensor) -> Tensor:\n"
    << shape_check(method, "z", {-1, options.latent()}, "latent codes") << "    h = torch.leaky_relu("
    << add_linear(module, vae.decoder_hidden, prefix + "decoder_hidden", "z") << ", " << literal(kSlope) << ")\n"
    << "    return torch.tanh(" << add_linear(module, vae.decoder_out, prefix + "decoder_out", "h")
    << ").view([z.size(0), " << options.vertices() << ", " << options.features() << "])\n\n";
  return s.str();
}

std::string add_normaliser(torch::jit::Module& module, const torch::Tensor& normaliser_min,
                           const torch::Tensor& normaliser_max, const std::string& prefix) {
  check_vae_prefix(prefix);
  const std::string where = "normaliser";
  if (!normaliser_min.defined() || !normaliser_max.defined() || normaliser_min.dim() != 2 ||
      normaliser_min.sizes() != normaliser_max.sizes()) {
    throw Error(where, "expected min and max of one shape [V, F], got " +
                           (normaliser_min.defined() ? c10::str(normaliser_min.sizes()) : std::string("none")) +
                           " and " +
                           (normaliser_max.defined() ? c10::str(normaliser_max.sizes()) : std::string("none")));
  }
  const torch::Tensor lo = frozen(normaliser_min), hi = frozen(normaliser_max);
  if (!torch::isfinite(lo).all().item<bool>() || !torch::isfinite(hi).all().item<bool>()) {
    throw Error(where, "min and max must be finite");
  }
  const torch::Tensor bad = (hi <= lo).nonzero();
  if (bad.size(0) > 0) {
    const int64_t vertex = bad[0][0].item<int64_t>(), channel = bad[0][1].item<int64_t>();
    throw Error(where, "max must exceed min everywhere; at vertex " + str(vertex) + ", channel " + str(channel) +
                           " min is " + literal(lo[vertex][channel].item<double>()) + " and max " +
                           literal(hi[vertex][channel].item<double>()));
  }
  module.register_buffer(prefix + "normaliser_min", lo);
  module.register_buffer(prefix + "normaliser_max", hi);

  const std::vector<int64_t> shape{-1, lo.size(0), lo.size(1)};
  const std::string bound = literal(kBound), width = literal(2 * kBound);
  const std::string ranges = "    lo = self." + prefix + "normaliser_min\n    hi = self." + prefix + "normaliser_max\n";
  // Shapes [..., V, F]: check the last two sizes only.
  auto check = [&](const std::string& method, const std::string& var, const std::string& meaning) {
    return "    assert " + var + ".dim() >= 2 and " + var + ".size(-2) == " + str(lo.size(0)) + " and " + var +
           ".size(-1) == " + str(lo.size(1)) + ", \"" + method + ": expected " + var + " of shape [..., " +
           str(lo.size(0)) + ", " + str(lo.size(1)) + "] (" + meaning + "), got \" + str(" + var + ".shape)\n";
  };
  // The same operations, in the same order, as Normaliser::normalise / denormalise.
  return "def " + prefix + "normalise(self, x: Tensor) -> Tensor:\n" +
         check(prefix + "normalise", "x", "raw DR features") + ranges + "    return (x - lo) * (" + width +
         " / (hi - lo)) - " + bound + "\n\n" + "def " + prefix + "denormalise(self, y: Tensor) -> Tensor:\n" +
         check(prefix + "denormalise", "y", "normalised features") + ranges + "    return (y + " + bound +
         ") * ((hi - lo) / " + width + ") + lo\n\n";
}

void add_metadata_attributes(torch::jit::Module& module, const VaeExportMetadata& metadata, const std::string& prefix) {
  check_vae_prefix(prefix);
  const auto text = c10::StringType::get();
  const auto integer = c10::IntType::get();
  module.register_attribute(prefix + "kind", text, metadata.kind);
  module.register_attribute(prefix + "name", text, metadata.name);
  module.register_attribute(prefix + "fingerprint", text, metadata.fingerprint);
  module.register_attribute(prefix + "version", text, metadata.software_version);
  module.register_attribute(prefix + "created", text, metadata.created);
  module.register_attribute(prefix + "vertices", integer, metadata.vertices);
  module.register_attribute(prefix + "latent", integer, metadata.latent);
  module.register_attribute(prefix + "features", integer, metadata.features);
}

std::string vae_metadata_json(const VaeExportMetadata& metadata, const std::string& part,
                              const MeshVaeOptions* architecture) {
  json document = {
      {"format", kFormat},
      {"format_version", kFormatVersion},
      {"part", part},
      {"kind", metadata.kind},
      {"name", metadata.name},
      {"fingerprint", metadata.fingerprint},
      {"software_version", metadata.software_version},
      {"created", metadata.created},
      {"vertices", metadata.vertices},
      {"latent", metadata.latent},
      {"features", metadata.features},
      {"normalisation", "normalise(x) = " + literal(2 * kBound) +
                            " (x - normaliser_min) / (normaliser_max - "
                            "normaliser_min) - " +
                            literal(kBound)},
  };
  if (architecture) {
    document["architecture"] = {
        {"channels", architecture->channels()}, {"hidden", architecture->hidden()}, {"order", architecture->order()}};
  }
  return document.dump(2) + "\n";
}

VaeExportMetadata parse_vae_metadata_json(const std::string& text, const std::string& where) {
  const JsonFields fields{where, kMetadataFile};
  const json document = fields.parse(text);
  const auto format = document.find("format");
  if (format == document.end() || *format != kFormat) {
    throw Error(where,
                std::string("not a retarget VAE export: ") + kMetadataFile + " has no \"format\": \"" + kFormat + "\"");
  }
  const int64_t version = fields.get<int64_t>(document, "format_version");
  if (version > kFormatVersion) {
    throw Error(where, "written in VAE export format " + str(version) +
                           " by a newer retarget; this build reads up to " + str(kFormatVersion));
  }
  VaeExportMetadata metadata;
  metadata.kind = fields.get<std::string>(document, "kind");
  metadata.name = fields.get<std::string>(document, "name");
  metadata.fingerprint = fields.get<std::string>(document, "fingerprint");
  metadata.software_version = fields.get<std::string>(document, "software_version");
  metadata.created = fields.get<std::string>(document, "created");
  metadata.vertices = fields.get<int64_t>(document, "vertices");
  metadata.latent = fields.get<int64_t>(document, "latent");
  metadata.features = fields.get<int64_t>(document, "features");
  try {
    metadata.validate(kMetadataFile);
  } catch (const Error& e) {
    throw Error(where, e.what());
  }
  return metadata;
}

void save_module_atomically(const torch::jit::Module& module, const std::string& path,
                            const torch::jit::ExtraFilesMap& extra_files) {
  const std::string temporary = temporary_path_for(path);
  try {
    module.save(temporary, extra_files);
  } catch (const std::exception& e) {
    discard_temporary_file(temporary);
    throw Error(path, "cannot write the TorchScript module: " + first_line(e));
  }
  commit_temporary_file(temporary, path);
}

void export_vae(MeshVaeImpl& vae, const torch::Tensor& normaliser_min, const torch::Tensor& normaliser_max,
                const VaeExportMetadata& metadata, const std::string& folder, const torch::Tensor& decoder_min,
                const torch::Tensor& decoder_max) {
  metadata.validate();
  const MeshVaeOptions& options = vae.options;
  require_metadata_matches(metadata, options);
  if (normaliser_min.defined() &&
      normaliser_min.sizes() != torch::IntArrayRef({options.vertices(), options.features()})) {
    throw Error("normaliser", "expected min and max of shape [" + str(options.vertices()) + ", " +
                                  str(options.features()) + "] for this VAE, got " + c10::str(normaliser_min.sizes()));
  }
  torch::NoGradGuard no_grad;

  torch::jit::Module encoder = make_script_module("__torch__.retarget.VaeEncoder");
  add_metadata_attributes(encoder, metadata, "");
  std::string source = add_normaliser(encoder, normaliser_min, normaliser_max, "");
  source += add_vae_encoder(encoder, vae, "");
  source += "def encode(self, x: Tensor) -> Tuple[Tensor, Tensor]:\n" +
            shape_check("encode", "x", {-1, options.vertices(), options.features()}, "raw DR features") +
            "    return self.encode_normalised(self.normalise(x))\n\n"
            "def forward(self, x: Tensor) -> Tensor:\n"
            "    mean, logvar = self.encode(x)\n"
            "    return mean\n";
  encoder.define(source);

  torch::jit::Module decoder = make_script_module("__torch__.retarget.VaeDecoder");
  add_metadata_attributes(decoder, metadata, "");
  const bool own_ranges = decoder_min.defined() && decoder_max.defined();
  if (own_ranges && decoder_min.sizes() != normaliser_min.sizes())
    throw Error("decoder normaliser", "expected min and max of shape " + c10::str(normaliser_min.sizes()) + ", got " +
                                          c10::str(decoder_min.sizes()));
  source =
      add_normaliser(decoder, own_ranges ? decoder_min : normaliser_min, own_ranges ? decoder_max : normaliser_max, "");
  source += add_vae_decoder(decoder, vae, "");
  source +=
      "def decode(self, z: Tensor) -> Tensor:\n"
      "    return self.denormalise(self.decode_normalised(z))\n\n"
      "def forward(self, z: Tensor) -> Tensor:\n"
      "    return self.decode(z)\n";
  decoder.define(source);

  const fs::path dir(folder);
  save_module_atomically(encoder, (dir / kEncoderFile).string(),
                         {{kMetadataFile, vae_metadata_json(metadata, "encoder", &options)}});
  save_module_atomically(decoder, (dir / kDecoderFile).string(),
                         {{kMetadataFile, vae_metadata_json(metadata, "decoder", &options)}});
}

ExportedVae load_exported_vae(const std::string& folder, const ExpectedTopology& expected) {
  const fs::path dir(folder);
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw Error(folder, "no such folder (expected an exported VAE: encoder.pt and decoder.pt)");
  }
  const std::string encoder_file = (dir / kEncoderFile).string(), decoder_file = (dir / kDecoderFile).string();
  LoadedPart encoder =
      load_part(encoder_file, "encoder", {"forward", "encode", "encode_normalised", "normalise", "denormalise"});
  const VaeExportMetadata& metadata = encoder.metadata;
  if (expected.vertices && *expected.vertices != metadata.vertices) {
    throw Error(encoder_file, "the VAE was exported for " + str(metadata.vertices) + " vertices, the mesh has " +
                                  str(*expected.vertices));
  }
  if (!expected.fingerprint.empty() && expected.fingerprint != metadata.fingerprint) {
    throw Error(encoder_file, "the VAE was exported for the topology with fingerprint " + metadata.fingerprint +
                                  ", the mesh has fingerprint " + expected.fingerprint + " (a different topology)");
  }
  LoadedPart decoder =
      load_part(decoder_file, "decoder", {"forward", "decode", "decode_normalised", "normalise", "denormalise"});
  require_same_export(encoder, decoder, decoder_file);
  return {std::move(encoder.module), std::move(decoder.module), encoder.metadata};
}

}  // namespace retarget
