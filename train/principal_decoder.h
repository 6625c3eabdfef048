// A VAE decoder started at its training targets' principal components instead of at random.
//
// An avatar's rig expressions span about as many directions as it has controllers, nearly
// linearly (the ICT head with 53 ARKit-named controllers: a linear map of the 53 weights
// reconstructs its normalised DR features to x0.12 of the neutral answer's L1, its first 53
// principal components to x0.14). A decoder started at random must find that subspace through
// a [hidden, V * 9] layer first; on rigs with many controllers and many vertices the quick and
// good profiles stopped before it had (validation L1 x0.98 of the neutral answer after 10
// epochs). Started here, the decoder is a linear model of the data from its first step:
//
//   decoder_out.bias          = m                    (the targets' mean, pre-tanh)
//   decoder_out.weight[:, 2i] = +s_i / 1.1 * v_i     (v_i: the i-th principal direction,
//   decoder_out.weight[:,2i+1]= -s_i / 1.1 * v_i      s_i: the spread of its coefficients)
//
// for i < min(hidden / 2, rank), every other column 0; and decoder_hidden's row 2i + 1 is the
// negation of its (random) row 2i, bias too. With LeakyReLU(0.1) between the layers a pair of
// pre-activations (a, -a) gives exactly 1.1 a, for either sign of a, so the decoder starts as the
// linear model m + sum_i a_i(z) s_i v_i, a_i linear in the code z, and can reach every point of
// the principal subspace. The encoder keeps its random start. Pre-tanh: the targets are
// atanh'ed (clamped to +-kPrincipalClamp) since the decoder ends in tanh.
//
// With an encoder skip (MeshVaeOptions::encoder_skip) only k <= latent directions are placed and
// decoder_hidden's pair rows are (e_i, -e_i), bias 0: a_i(z) = z_i, so the code's first k
// coordinates are the rank-k principal coefficients (in units of their spread) and
// train/principal_encoder.h can start the encoder at them: the untrained VAE is then the
// rank-k principal reconstruction, the best linear one of that rank.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <vector>

#include "models/mesh_vae.h"

namespace retarget {

constexpr double kPrincipalClamp = 0.99;  // |target| bound before atanh

struct PrincipalDecoderStart {
  int64_t components = 0;  // principal directions placed in the decoder, k
  double explained = 0;    // fraction of the targets' pre-tanh variance they explain, [0, 1]
  // [N, k] float32: each row used's coefficients along the k directions in units of their
  // spread (mean 0, mean square 1 per column); undefined when k = 0. With an encoder skip these
  // are the codes that decode to the row's principal reconstruction.
  torch::Tensor codes;
  std::vector<int64_t> positions;  // [N]: codes' row j is rows[positions[j]]
};

// targets: [M, V, F] float32 normalised decoder targets (V, F as vae.options); rows: the
// training rows of `targets` to take the components from (repeats weigh a row more; at least
// 2, each in [0, M); beyond 4,096 rows an evenly spaced 4,096 are used). Works in column
// blocks, never holding a second [rows, V * F] copy.
// Throws retarget::Error on shape mismatch or fewer than 2 rows.
PrincipalDecoderStart start_decoder_at_principal_components(MeshVaeImpl& vae, const torch::Tensor& targets,
                                                            const std::vector<int64_t>& rows);

}  // namespace retarget
