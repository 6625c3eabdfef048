#include "models/mesh_vae.h"

#include <catch2/catch.hpp>

#include "core/error.h"
#include "models/graph_operator.h"
#include "models/losses.h"
#include "tests/models/model_test_support.h"

namespace retarget {
namespace {

constexpr int64_t kRows = 3, kCols = 4, kV = kRows * kCols;

MeshVaeOptions small_options() { return MeshVaeOptions(kV).channels({9, 16, 8, 1}).hidden(32).latent(5); }

TEST_CASE("MeshVae with the default architecture runs forward and backward", "[mesh_vae]") {
  torch::manual_seed(4);
  const torch::Tensor l = graph_operator(test::grid_edges(kRows, kCols), kV);
  MeshVae vae(l, MeshVaeOptions(kV));  // channels 9-128-64-64-64-1, hidden 300, latent 25
  CHECK(vae->convs->size() == 5);
  const torch::Tensor x = torch::rand({2, kV, 9}) * 2 - 1;
  const VaeOutput out = vae(x, true);
  CHECK(out.reconstruction.sizes() == torch::IntArrayRef({2, kV, 9}));
  CHECK(out.mean.sizes() == torch::IntArrayRef({2, 25}));
  CHECK(out.logvar.sizes() == torch::IntArrayRef({2, 25}));
  CHECK(out.z.sizes() == torch::IntArrayRef({2, 25}));
  CHECK(out.reconstruction.abs().max().item<double>() < 1.0);  // tanh
  vae_loss(out.reconstruction, x, out.mean, out.logvar, 1.0).total.backward();
  test::check_gradients(*vae);
  // The operator is a buffer of every graph conv, never a parameter.
  for (const auto& p : vae->named_parameters()) CHECK(p.key().find("laplacian") == std::string::npos);
}

TEST_CASE("MeshVae encode/decode shapes; no-sample forward is deterministic", "[mesh_vae]") {
  torch::manual_seed(5);
  MeshVae vae(graph_operator(test::grid_edges(kRows, kCols), kV), small_options());
  vae->eval();
  const torch::Tensor x = torch::rand({3, kV, 9}) * 2 - 1;
  const VaeEncoding code = vae->encode(x);
  CHECK(code.mean.sizes() == torch::IntArrayRef({3, 5}));
  CHECK(vae->decode(code.mean).sizes() == torch::IntArrayRef({3, kV, 9}));
  const VaeOutput a = vae(x, false), b = vae(x, false);
  CHECK(torch::equal(a.reconstruction, b.reconstruction));
  CHECK(torch::equal(a.z, a.mean));
  CHECK(torch::allclose(a.reconstruction, vae->decode(code.mean)));
  const VaeOutput s = vae(x, true);
  CHECK_FALSE(torch::equal(s.z, s.mean));
  // HumanVae is the same module family.
  HumanVae human(graph_operator(test::grid_edges(kRows, kCols), kV), small_options());
  CHECK(human(x, false).reconstruction.sizes() == x.sizes());
}

TEST_CASE("MeshVae: 30 Adam steps lower the loss on a tiny problem", "[mesh_vae]") {
  torch::manual_seed(6);
  MeshVae vae(graph_operator(test::grid_edges(kRows, kCols), kV), small_options());
  // Eight shapes spanned by two fixed per-vertex patterns: learnable, unlike pure noise.
  const torch::Tensor patterns = torch::rand({2, kV * 9}) - 0.5;
  const torch::Tensor data = torch::matmul(torch::rand({8, 2}) * 2 - 1, patterns).view({8, kV, 9});
  auto eval_loss = [&] {
    torch::NoGradGuard no_grad;
    const VaeOutput out = vae(data, false);
    return vae_loss(out.reconstruction, data, out.mean, out.logvar, 1e-3).total.item<double>();
  };
  const double before = eval_loss();
  torch::optim::Adam adam(vae->parameters(), torch::optim::AdamOptions(1e-2));
  for (int step = 0; step < 30; ++step) {
    adam.zero_grad();
    const VaeOutput out = vae(data, true);
    vae_loss(out.reconstruction, data, out.mean, out.logvar, 1e-3).total.backward();
    adam.step();
  }
  const double after = eval_loss();
  INFO("loss before " << before << ", after " << after);
  CHECK(after < 0.85 * before);  // seen: 0.209 -> 0.145
}

TEST_CASE("MeshVae rejects bad options with a message", "[mesh_vae]") {
  const torch::Tensor l = graph_operator(test::grid_edges(kRows, kCols), kV);
  CHECK_THROWS_AS(MeshVae(l, small_options().latent(0)), Error);
  CHECK_THROWS_WITH(MeshVae(l, small_options().latent(0)), "mesh_vae.latent: expected a positive number, got 0");
  CHECK_THROWS_WITH(MeshVae(l, small_options().hidden(-3)), "mesh_vae.hidden: expected a positive number, got -3");
  CHECK_THROWS_WITH(MeshVae(l, small_options().order(-1)), "mesh_vae.order: expected a number >= 0, got -1");
  CHECK_THROWS_WITH(MeshVae(l, small_options().channels({9, 0, 1})),
                    "mesh_vae.channels[1]: expected a positive number, got 0");
  CHECK_THROWS_WITH(MeshVae(l, small_options().channels({9})),
                    "mesh_vae.channels: expected at least two widths (input features and one graph conv), got 1");
  CHECK_THROWS_WITH(MeshVae(l, MeshVaeOptions(0)), "mesh_vae.vertices: expected a positive number, got 0");
  CHECK_THROWS_WITH(MeshVae(l, MeshVaeOptions(10)), "mesh_vae: expected a [10, 10] graph operator, got [12, 12]");
}

}  // namespace
}  // namespace retarget
