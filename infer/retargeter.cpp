#include "infer/retargeter.h"

#include <utility>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "geometry/part_motion.h"

namespace retarget {

namespace {

DrOptions human_dr_options(const LoadedBundle& bundle, const RetargeterOptions& options) {
  DrOptions dr = bundle.metadata.human.dr;
  dr.threads = options.threads;
  return dr;
}

ReconstructionOptions avatar_reconstruction_options(const LoadedBundle& bundle, const RetargeterOptions& options) {
  ReconstructionOptions r;
  r.weighting = bundle.metadata.avatar.dr.weighting;  // the avatar features' own convention
  r.align_to_rest = options.align_to_rest;
  r.threads = options.threads;
  // The avatar's still region stays at rest (bundles that carry it).
  if (options.anchors)
    r.anchors.assign(bundle.metadata.avatar.still_vertices.begin(), bundle.metadata.avatar.still_vertices.end());
  if (options.part_motion && bundle.rig)
    if (std::vector<std::vector<int>> parts = rig_parts_to_move(*bundle.rig); !parts.empty())
      r.parts = std::make_shared<const PartMotion>(*bundle.rig, std::move(parts));
  return r;
}

const RetargeterOptions& validated(const RetargeterOptions& options) {
  options.validate();
  return options;
}

}  // namespace

void RetargeterOptions::validate(const std::string& key_path) const {
  require_non_negative(threads, key_path + ".threads");
}

Retargeter::Retargeter(LoadedBundle bundle, const RetargeterOptions& options)
    : bundle_(std::move(bundle)),
      options_(validated(options)),
      human_features_(bundle_.human_rest, human_dr_options(bundle_, options_)),
      avatar_reconstruction_(bundle_.avatar_rest, avatar_reconstruction_options(bundle_, options_)) {
  if (options_.native_network && bundle_.module.find_method("translate") && bundle_.module.find_method("decode_avatar"))
    native_network_ = NativeNetwork::of_bundle(bundle_.module, options_.precision);
  if (!native_network_) {
    log::info("network: the bundle's TorchScript");
    return;
  }
  if (native_network_->precision() != options_.precision)
    log::warn("precision {}: {}; the network runs in {}", to_string(options_.precision),
              network_products_kernel(options_.precision), to_string(native_network_->precision()));
  log::info("network: native, {} products: {}, loops: {}", to_string(native_network_->precision()),
            network_products_kernel(native_network_->precision()), network_loops_kernel());
}

torch::Tensor Retargeter::features(const std::vector<const Positions*>& human) const {
  torch::Tensor out = torch::empty({static_cast<int64_t>(human.size()), human_vertices(), kDrWidth}, torch::kFloat32);
  if (!human.empty()) human_features_.compute_batch(human, out.data_ptr<float>());
  return out;
}

torch::Tensor Retargeter::translate(const torch::Tensor& human_features) {
  c10::InferenceMode inference;
  if (!native_network_) return bundle_.module.forward({human_features}).toTensor();
  // forward() = decode_avatar(translate(encode_human(x))), the encoder and decoder native.
  const torch::Tensor z = native_network_->encode_human(human_features);
  const torch::IValue code = bundle_.module.run_method("translate", z);
  const torch::Tensor y = native_network_->decodes() ? native_network_->decode_avatar(code.toTensor())
                                                     : bundle_.module.run_method("decode_avatar", code).toTensor();
  TORCH_CHECK(y.dim() == 3 && y.size(1) == avatar_vertices() && y.size(2) == kDrWidth,
              "forward: expected y of shape [B, ", avatar_vertices(), ", 9] (raw avatar DR features), got ", y.sizes());
  return y;
}

std::vector<Positions> Retargeter::reconstruct(const torch::Tensor& avatar_features) const {
  TORCH_CHECK(
      avatar_features.dim() == 3 && avatar_features.size(1) == avatar_vertices() && avatar_features.size(2) == kDrWidth,
      "Retargeter::reconstruct: expected [B, ", avatar_vertices(), ", 9], got ", avatar_features.sizes());
  const torch::Tensor features = avatar_features.to(torch::kCPU, torch::kFloat32).contiguous();
  return avatar_reconstruction_.reconstruct_batch(features.data_ptr<float>(), static_cast<int>(features.size(0)));
}

std::vector<Positions> Retargeter::retarget(const std::vector<const Positions*>& human) {
  return reconstruct(translate(features(human)));
}

}  // namespace retarget
