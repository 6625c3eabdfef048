#include "data/normaliser.h"

#include <catch2/catch.hpp>

#include "core/error.h"
#include "core/tensor_io.h"
#include "test_support.h"

using namespace retarget;

namespace {
torch::Tensor random_features(int64_t n, int64_t v, uint64_t seed) {
  torch::manual_seed(seed);
  return torch::randn({n, v, 9}) * torch::linspace(0.01, 2.0, 9) + 0.3;
}
}  // namespace

TEST_CASE("normalised training features span [-0.9, 0.9] per vertex and channel", "[normaliser]") {
  const torch::Tensor train = random_features(50, 7, 1);
  const Normaliser n = Normaliser::fit(train);
  CHECK(n.min.sizes() == c10::IntArrayRef({7, 9}));
  CHECK(n.max.scalar_type() == torch::kFloat32);
  CHECK(n.vertex_count() == 7);
  const torch::Tensor y = n.normalise(train);
  CHECK(y.sizes() == train.sizes());
  CHECK(y.min().item<double>() >= -0.9 - 1e-6);
  CHECK(y.max().item<double>() <= 0.9 + 1e-6);
  // Every dimension reaches both ends.
  CHECK(torch::allclose(std::get<0>(y.min(0)), torch::full({7, 9}, -0.9f), 1e-5, 1e-5));
  CHECK(torch::allclose(std::get<0>(y.max(0)), torch::full({7, 9}, 0.9f), 1e-5, 1e-5));
  // The inverse, also on data outside the training range and on flat [N, V * 9] rows.
  const torch::Tensor other = random_features(4, 7, 2) * 3;
  CHECK(torch::allclose(n.denormalise(n.normalise(other)), other, 1e-4, 1e-5));
  const torch::Tensor flat = other.reshape({4, 63});
  CHECK(n.normalise(flat).sizes() == flat.sizes());
  CHECK(torch::allclose(n.normalise(flat), n.normalise(other).reshape({4, 63})));
  CHECK(torch::allclose(n.normalise(other[0]), n.normalise(other)[0]));
  // Doubles stay doubles.
  CHECK(n.normalise(other.to(torch::kFloat64)).scalar_type() == torch::kFloat64);
}

TEST_CASE("constant dimensions get a range of 1e-5 about their value", "[normaliser]") {
  torch::Tensor train = random_features(20, 3, 3);
  train.select(1, 1).select(1, 4).fill_(0.25f);  // vertex 1, channel 4: constant
  train.select(1, 2).fill_(0);                   // vertex 2: all zeros (rest everywhere)
  train[0][0][0] = 1e-6f;
  train.select(1, 0).select(1, 0).slice(0, 1).fill_(0);  // vertex 0, channel 0: range 1e-6
  const Normaliser n = Normaliser::fit(train);
  const torch::Tensor range = n.max - n.min;
  CHECK(range.min().item<double>() >= 1e-5 * (1 - 1e-3));
  CHECK(range[1][4].item<double>() == Approx(1e-5).epsilon(1e-2));
  CHECK(0.5 * (n.min[1][4] + n.max[1][4]).item<double>() == Approx(0.25).epsilon(1e-6));
  CHECK(n.min[2][0].item<double>() == Approx(-0.5e-5).epsilon(1e-3));
  CHECK(n.max[0][0].item<double>() == Approx(1e-6 / 2 + 0.5e-5).epsilon(1e-2));
  const torch::Tensor y = n.normalise(train);
  CHECK(torch::isfinite(y).all().item<bool>());
  CHECK(y.abs().max().item<double>() <= 0.9 + 1e-4);
  CHECK(y.select(1, 2).abs().max().item<double>() < 1e-3);  // constants map to the middle
  CHECK(torch::allclose(n.denormalise(y), train, 1e-5, 1e-7));
}

TEST_CASE("normalise_within_range: constant dimensions take their training value, others are clamped", "[normaliser]") {
  torch::Tensor train = random_features(20, 3, 5);
  train.select(1, 1).select(1, 4).fill_(0.25f);  // vertex 1, channel 4: constant in training
  const Normaliser n = Normaliser::fit(train);
  // Another sample: inside the range in most dimensions, far outside in a few.
  torch::Tensor other = train.slice(0, 0, 2).clone();
  other[0][1][4] = 0.2501f;  // the constant dimension moved a little: normalise gives ~18
  other[0][0][0] = 1e3f;     // far above vertex 0, channel 0's range
  other[1][2][8] = -1e3f;    // far below
  const torch::Tensor plain = n.normalise(other);
  REQUIRE(plain[0][1][4].item<double>() > 10);
  const torch::Tensor y = n.normalise_within_range(other);
  CHECK(y.sizes() == other.sizes());
  CHECK(y[0][1][4].item<double>() == 0.0);
  CHECK(y[1][1][4].item<double>() == 0.0);
  CHECK(y[0][0][0].item<double>() == Approx(0.9));
  CHECK(y[1][2][8].item<double>() == Approx(-0.9));
  // Everywhere else it is normalise(): the training samples are within [-0.9, 0.9] already.
  torch::Tensor expected = plain.clamp(-0.9, 0.9);
  expected.select(1, 1).select(1, 4).fill_(0);
  CHECK(torch::allclose(y, expected, 1e-6, 1e-6));
  // The flat layout [N, V * 9] gives the same values.
  CHECK(torch::allclose(n.normalise_within_range(other.reshape({2, 27})), y.reshape({2, 27})));
}

TEST_CASE("fitting on selected rows equals fitting on their copy", "[normaliser]") {
  const torch::Tensor features = random_features(600, 4, 4);  // more rows than one chunk
  std::vector<int64_t> rows;
  for (int64_t i = 0; i < 600; i += 2) rows.push_back(i);
  rows.push_back(599);
  const Normaliser a = Normaliser::fit(features, rows);
  const Normaliser b = Normaliser::fit(features.index_select(0, torch::tensor(rows)));
  CHECK(torch::equal(a.min, b.min));
  CHECK(torch::equal(a.max, b.max));
  // With extra samples (the human targets): as if they were more rows.
  const torch::Tensor extra = random_features(3, 4, 8) * 4;
  const Normaliser c = Normaliser::fit(features, rows, extra);
  const Normaliser d = Normaliser::fit(torch::cat({features.index_select(0, torch::tensor(rows)), extra}));
  CHECK(torch::equal(c.min, d.min));
  CHECK(torch::equal(c.max, d.max));
  CHECK(!torch::equal(c.max, a.max));
  CHECK_THROWS_WITH(Normaliser::fit(features, {}), Catch::Contains("no training samples"));
  CHECK_THROWS_WITH(Normaliser::fit(torch::zeros({0, 4, 9})), Catch::Contains("no training samples"));
  torch::Tensor bad = features.clone();
  bad[3][1][2] = NAN;
  CHECK_THROWS_WITH(Normaliser::fit(bad), Catch::Contains("NaN"));
}

TEST_CASE("normalisation is differentiable", "[normaliser]") {
  const Normaliser n = Normaliser::fit(random_features(10, 2, 5));
  const torch::Tensor x = random_features(3, 2, 6).requires_grad_(true);
  n.denormalise(n.normalise(x)).sum().backward();
  CHECK(torch::allclose(x.grad(), torch::ones_like(x), 1e-4, 1e-4));
}

TEST_CASE("a normaliser round-trips through its file, and bad files are refused", "[normaliser]") {
  const auto dir = test::scratch_dir("normaliser_file");
  const Normaliser n = Normaliser::fit(random_features(10, 5, 7));
  const std::string path = (dir / "normaliser.pt").string();
  n.save(path);
  const Normaliser back = Normaliser::load(path);
  CHECK(torch::equal(back.min, n.min));
  CHECK(torch::equal(back.max, n.max));

  const std::string missing = (dir / "missing.pt").string();
  save_tensors(missing, {{"min", n.min}});
  CHECK_THROWS_WITH(Normaliser::load(missing), Catch::Contains("missing.pt") && Catch::Contains("\"max\""));
  const std::string shape = (dir / "shape.pt").string();
  save_tensors(shape, {{"min", n.min.reshape({-1})}, {"max", n.max.reshape({-1})}});
  CHECK_THROWS_WITH(Normaliser::load(shape), Catch::Contains("shape.pt") && Catch::Contains("[V, 9]"));
  const std::string swapped = (dir / "swapped.pt").string();
  save_tensors(swapped, {{"min", n.max}, {"max", n.min}});
  CHECK_THROWS_WITH(Normaliser::load(swapped), Catch::Contains("max < min"));
  const std::string bound = (dir / "bound.pt").string();
  save_tensors(bound, {{"min", n.min}, {"max", n.max}, {"bound", torch::tensor(1.0, torch::kFloat64)}});
  CHECK_THROWS_WITH(Normaliser::load(bound), Catch::Contains("bound"));
  CHECK_THROWS_WITH(Normaliser::load((dir / "none.pt").string()), Catch::Contains("none.pt"));
}

TEST_CASE("widened_to keeps every range at least a fraction of a reference range", "[normaliser]") {
  const torch::Tensor wide = random_features(50, 5, 3);
  const Normaliser reference = Normaliser::fit(wide);
  // Narrow ranges: a tenth of the data, and one dimension constant.
  torch::Tensor narrow = wide.slice(0, 0, 5) * 0.01;
  narrow.select(2, 4).fill_(0.25);
  const Normaliser tight = Normaliser::fit(narrow);
  const Normaliser floored = tight.widened_to(reference, 0.1);
  const torch::Tensor range = floored.max - floored.min, reference_range = reference.max - reference.min;
  CHECK((range >= 0.1 * reference_range - 1e-6).all().item<bool>());
  // Centres stay; a range already wider than the floor stays as it was.
  CHECK(torch::allclose(floored.max + floored.min, tight.max + tight.min, 1e-5, 1e-5));
  const Normaliser loose = tight.widened_to(reference, 0.0);
  CHECK(torch::equal(loose.min, tight.min));
  CHECK(torch::equal(loose.max, tight.max));
  // The constant dimension now spans a tenth of the reference's range about its value.
  CHECK(floored.max[0][4].item<double>() - floored.min[0][4].item<double>() ==
        Approx(0.1 * reference_range[0][4].item<double>()).epsilon(1e-4));
}
