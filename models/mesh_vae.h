// The mesh VAE of the method notes ("Networks"): a Chebyshev graph-convolutional encoder and an
// MLP decoder over per-vertex deformation-representation (DR) features.
//
// The avatar VAE and the human expression VAE (the expression branch of Jiang et al. 2019) are
// the same module family; they differ only in data and loss, not in architecture:
//   - avatar VAE: input = target = the avatar's DR feature; loss L1 + kl_weight * KL.
//   - human VAE: input = a person's expression DR feature (relative to the mean neutral face),
//     target = the DR feature of the identity-averaged shape of that expression; loss
//     L1 + 1e-5 * KL. See vae_loss() in models/losses.h.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <string>
#include <vector>

#include "models/chebyshev_conv.h"

namespace retarget {

constexpr double kMeshVaeSlope = 0.1;  // negative slope of every LeakyReLU (method notes)

// Bounds checked before anything is allocated (a config's `model.channels: [9, 2147483648, ...]`
// must be an error, not an allocation failure): every width and the latent size at most
// kMaxLayerWidth, the Chebyshev order at most kMaxChebyshevOrder, and the whole model at most
// kMaxModelParameters float32 parameters (4 GiB).
constexpr int64_t kMaxLayerWidth = 65536;
constexpr int64_t kMaxChebyshevOrder = 16;
constexpr int64_t kMaxModelParameters = int64_t{1} << 30;

struct MeshVaeOptions {
  explicit MeshVaeOptions(int64_t vertices) : vertices_(vertices) {}
  // Throws retarget::Error naming key_path.<option> for a value out of range (the bounds above;
  // the parameter bound names key_path itself).
  void validate(const std::string& key_path = "mesh_vae") const;
  // Trainable parameters of the module these options build (exact; no overflow for widths
  // within kMaxLayerWidth).
  int64_t parameter_count() const;
  int64_t features() const { return channels_.front(); }  // F = channels.front()

  TORCH_ARG(int64_t, vertices);  // V of the mesh graph, > 0
  // Graph-conv widths; channels.front() is the per-vertex feature width F (9 for DR features),
  // which the decoder also outputs. LeakyReLU(0.1) between convs, tanh after the last.
  TORCH_ARG(std::vector<int64_t>, channels) = std::vector<int64_t>{9, 128, 64, 64, 64, 1};
  TORCH_ARG(int64_t, hidden) = 300;  // width of the encoder's and decoder's dense hidden layer
  TORCH_ARG(int64_t, latent) = 25;   // latent code size
  TORCH_ARG(int64_t, order) = 2;     // Chebyshev order of every graph conv (T0..T2)
  // Beyond the paper: a dense linear map from the normalised input [B, V * F] (flattened as
  // [B, V, F]) straight to the code's mean, added to the graph-conv path's mean_head. The paper's
  // encoder narrows every vertex to one channel before its dense layer; the skip lets a linear
  // model of all F features reach the code. It is fitted, not trained: its parameters do not
  // require gradients (train/principal_encoder.h fits it to the principal codes).
  TORCH_ARG(bool, encoder_skip) = false;
};

// Named results ([B, V, F] and [B, latent] float32).
struct VaeEncoding {
  torch::Tensor mean;    // [B, latent]
  torch::Tensor logvar;  // [B, latent], log of the posterior variance
};

struct VaeOutput {
  torch::Tensor reconstruction;  // [B, V, F], in (-1, 1) (tanh)
  torch::Tensor mean;            // [B, latent]
  torch::Tensor logvar;          // [B, latent]
  torch::Tensor z;               // [B, latent], the code that was decoded
};

class MeshVaeImpl : public torch::nn::Cloneable<MeshVaeImpl> {
 public:
  // laplacian: [V, V] rescaled Laplacian L~ from graph_operator(), V == options.vertices().
  MeshVaeImpl(torch::Tensor laplacian, const MeshVaeOptions& options);

  void reset() override;

  // x: [B, V, F] -> mean, logvar [B, latent].
  VaeEncoding encode(const torch::Tensor& x);
  // z: [B, latent] -> [B, V, F].
  torch::Tensor decode(const torch::Tensor& z);
  // x: [B, V, F]. sample: z = mean + exp(logvar / 2) * N(0, I) (reparameterisation, uses the
  // global torch RNG); otherwise z = mean, which is deterministic.
  VaeOutput forward(const torch::Tensor& x, bool sample = true);
  // The same with the standard normal draws given: z = mean + exp(logvar / 2) * noise, noise
  // [B, latent] (a data-parallel rank's rows of the whole batch's draws).
  VaeOutput forward_with_noise(const torch::Tensor& x, const torch::Tensor& noise);

  MeshVaeOptions options;
  torch::Tensor laplacian;
  torch::nn::ModuleList convs{nullptr};
  torch::nn::Linear encoder_hidden{nullptr}, mean_head{nullptr}, logvar_head{nullptr};
  torch::nn::Linear encoder_skip{nullptr};  // [V * F] -> [latent]; only with options.encoder_skip()
  torch::nn::Linear decoder_hidden{nullptr}, decoder_out{nullptr};
};

TORCH_MODULE(MeshVae);

// The human expression VAE: same architecture, different data and loss weight (see above).
using HumanVae = MeshVae;
using HumanVaeOptions = MeshVaeOptions;

}  // namespace retarget
