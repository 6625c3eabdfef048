#include "models/mesh_vae.h"

#include <fmt/format.h>

#include <utility>

#include "core/config.h"
#include "core/error.h"

namespace retarget {

namespace {
constexpr double kSlope = kMeshVaeSlope;
}

void MeshVaeOptions::validate(const std::string& key_path) const {
  require_positive(static_cast<double>(vertices_), key_path + ".vertices");
  require(channels_.size() >= 2, key_path + ".channels",
          "expected at least two widths (input features and one graph conv), got " + std::to_string(channels_.size()));
  for (size_t i = 0; i < channels_.size(); ++i) {
    require_positive(static_cast<double>(channels_[i]), key_path + ".channels[" + std::to_string(i) + "]");
  }
  require_positive(static_cast<double>(hidden_), key_path + ".hidden");
  require_positive(static_cast<double>(latent_), key_path + ".latent");
  require_non_negative(static_cast<double>(order_), key_path + ".order");
  auto at_most = [&](int64_t value, int64_t bound, const std::string& key) {
    require(value <= bound, key, fmt::format("expected at most {}, got {}", bound, value));
  };
  for (size_t i = 0; i < channels_.size(); ++i)
    at_most(channels_[i], kMaxLayerWidth, key_path + ".channels[" + std::to_string(i) + "]");
  at_most(hidden_, kMaxLayerWidth, key_path + ".hidden");
  at_most(latent_, kMaxLayerWidth, key_path + ".latent");
  at_most(order_, kMaxChebyshevOrder, key_path + ".order");
  const int64_t parameters = parameter_count();
  // A config is checked before its dataset is read: vertices_ is then 1, and the widths alone
  // (the count for a 1-vertex mesh) already exceed the bound.
  const std::string mesh = vertices_ > 1 ? fmt::format("with the dataset's {} vertices", vertices_)
                                         : std::string("before any vertex is counted (for a 1-vertex mesh)");
  require(parameters <= kMaxModelParameters, key_path,
          fmt::format("these widths make a model of {} parameters ({:.1f} GiB) {}; the bound is {} (4 GiB): use "
                      "narrower layers",
                      parameters, parameters * 4.0 / (1 << 30), mesh, kMaxModelParameters));
}

int64_t MeshVaeOptions::parameter_count() const {
  // Widths are <= 2^16 and V is a mesh's vertex count, so every product fits in int64_t.
  int64_t count = 0;
  for (size_t i = 0; i + 1 < channels_.size(); ++i)
    count += (order_ + 1) * channels_[i] * channels_[i + 1] + channels_[i + 1];      // weights + bias
  count += vertices_ * channels_.back() * hidden_ + hidden_;                         // encoder_hidden
  count += 2 * (hidden_ * latent_ + latent_);                                        // mean, logvar heads
  if (encoder_skip_) count += vertices_ * channels_.front() * latent_ + latent_;     // encoder_skip
  count += latent_ * hidden_ + hidden_;                                              // decoder_hidden
  count += hidden_ * vertices_ * channels_.front() + vertices_ * channels_.front();  // decoder_out
  return count;
}

MeshVaeImpl::MeshVaeImpl(torch::Tensor laplacian_, const MeshVaeOptions& options_)
    : options(options_), laplacian(std::move(laplacian_)) {
  options.validate();
  if (laplacian.dim() != 2 || laplacian.size(0) != options.vertices() || laplacian.size(1) != options.vertices()) {
    throw Error("mesh_vae", "expected a [" + std::to_string(options.vertices()) + ", " +
                                std::to_string(options.vertices()) + "] graph operator, got " +
                                c10::str(laplacian.sizes()));
  }
  reset();
}

void MeshVaeImpl::reset() {
  const auto& ch = options.channels();
  const int64_t v = options.vertices();
  convs = register_module("convs", torch::nn::ModuleList());
  for (size_t i = 0; i + 1 < ch.size(); ++i) {
    convs->push_back(ChebyshevConv(laplacian, ChebyshevConvOptions(ch[i], ch[i + 1]).order(options.order())));
  }
  encoder_hidden = register_module("encoder_hidden", torch::nn::Linear(v * ch.back(), options.hidden()));
  mean_head = register_module("mean_head", torch::nn::Linear(options.hidden(), options.latent()));
  logvar_head = register_module("logvar_head", torch::nn::Linear(options.hidden(), options.latent()));
  if (options.encoder_skip()) {
    encoder_skip = register_module("encoder_skip", torch::nn::Linear(v * options.features(), options.latent()));
    // Fitted, not trained: Adam moves each of its V * F weights per input by about the learning
    // rate per step, which shifts a code by thousands of times that (measured: a start at
    // x0.13 of the neutral answer was x0.46 after one epoch).
    for (auto& p : encoder_skip->parameters()) p.set_requires_grad(false);
  }
  decoder_hidden = register_module("decoder_hidden", torch::nn::Linear(options.latent(), options.hidden()));
  decoder_out = register_module("decoder_out", torch::nn::Linear(options.hidden(), v * options.features()));
}

VaeEncoding MeshVaeImpl::encode(const torch::Tensor& x) {
  TORCH_CHECK(x.dim() == 3 && x.size(1) == options.vertices() && x.size(2) == options.features(),
              "MeshVae::encode: expected x [B, ", options.vertices(), ", ", options.features(), "], got ", x.sizes());
  torch::Tensor h = x;
  const size_t last = convs->size() - 1;
  for (size_t i = 0; i < convs->size(); ++i) {
    h = convs[i]->as<ChebyshevConvImpl>()->forward(h);
    h = i == last ? torch::tanh(h) : torch::leaky_relu(h, kSlope);
  }
  h = torch::leaky_relu(encoder_hidden->forward(h.flatten(1)), kSlope);
  torch::Tensor mean = mean_head->forward(h);
  if (encoder_skip) mean = mean + encoder_skip->forward(x.flatten(1));
  return {std::move(mean), logvar_head->forward(h)};
}

torch::Tensor MeshVaeImpl::decode(const torch::Tensor& z) {
  TORCH_CHECK(z.dim() == 2 && z.size(1) == options.latent(), "MeshVae::decode: expected z [B, ", options.latent(),
              "], got ", z.sizes());
  const torch::Tensor h = torch::leaky_relu(decoder_hidden->forward(z), kSlope);
  return torch::tanh(decoder_out->forward(h)).view({z.size(0), options.vertices(), options.features()});
}

VaeOutput MeshVaeImpl::forward(const torch::Tensor& x, bool sample) {
  VaeEncoding code = encode(x);
  torch::Tensor z = sample ? code.mean + torch::exp(0.5 * code.logvar) * torch::randn_like(code.mean) : code.mean;
  torch::Tensor reconstruction = decode(z);
  return {std::move(reconstruction), std::move(code.mean), std::move(code.logvar), std::move(z)};
}

VaeOutput MeshVaeImpl::forward_with_noise(const torch::Tensor& x, const torch::Tensor& noise) {
  VaeEncoding code = encode(x);
  TORCH_CHECK(noise.sizes() == code.mean.sizes(), "MeshVae: noise ", noise.sizes(), " for codes ", code.mean.sizes());
  torch::Tensor z = code.mean + torch::exp(0.5 * code.logvar) * noise;
  torch::Tensor reconstruction = decode(z);
  return {std::move(reconstruction), std::move(code.mean), std::move(code.logvar), std::move(z)};
}

}  // namespace retarget
