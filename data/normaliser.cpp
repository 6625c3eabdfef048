#include "data/normaliser.h"

#include <algorithm>

#include "core/error.h"
#include "core/tensor_io.h"
#include "geometry/dr_features.h"

namespace retarget {

namespace {

Normaliser from_extremes(torch::Tensor lo, torch::Tensor hi) {
  lo = lo.to(torch::kFloat64);
  hi = hi.to(torch::kFloat64);
  if (!torch::isfinite(lo).all().item<bool>() || !torch::isfinite(hi).all().item<bool>())
    throw Error("normaliser", "the training features contain NaN or infinite values");
  const torch::Tensor narrow = (hi - lo) < kMinimumRange;
  const torch::Tensor centre = 0.5 * (lo + hi);
  Normaliser n;
  n.min = torch::where(narrow, centre - 0.5 * kMinimumRange, lo).to(torch::kFloat32).contiguous();
  n.max = torch::where(narrow, centre + 0.5 * kMinimumRange, hi).to(torch::kFloat32).contiguous();
  return n;
}

void check_features(const torch::Tensor& f) {
  TORCH_CHECK(f.dim() == 3 && f.size(2) == kDrWidth, "normaliser: expected features [N, V, 9], got ", f.sizes());
  TORCH_CHECK(f.is_floating_point(), "normaliser: expected floating-point features");
}

}  // namespace

Normaliser Normaliser::widened_to(const Normaliser& reference, double fraction) const {
  TORCH_CHECK(reference.min.sizes() == min.sizes(), "normaliser: reference ranges of another shape");
  TORCH_CHECK(fraction >= 0 && fraction <= 1, "normaliser: fraction outside [0, 1]");
  const torch::Tensor lo = min.to(torch::kFloat64), hi = max.to(torch::kFloat64);
  const torch::Tensor floor = fraction * (reference.max - reference.min).to(torch::kFloat64);
  const torch::Tensor range = torch::maximum(hi - lo, floor), centre = 0.5 * (lo + hi);
  Normaliser n;
  n.min = (centre - 0.5 * range).to(torch::kFloat32).contiguous();
  n.max = (centre + 0.5 * range).to(torch::kFloat32).contiguous();
  return n;
}

Normaliser Normaliser::with_channel_floor(double fraction) const {
  TORCH_CHECK(fraction >= 0 && fraction <= 1, "normaliser: fraction outside [0, 1]");
  const torch::Tensor lo = min.to(torch::kFloat64), hi = max.to(torch::kFloat64);
  const torch::Tensor floor = fraction * std::get<0>((hi - lo).max(0, /*keepdim=*/true));  // [1, 9]
  const torch::Tensor range = torch::maximum(hi - lo, floor), centre = 0.5 * (lo + hi);
  Normaliser n;
  n.min = (centre - 0.5 * range).to(torch::kFloat32).contiguous();
  n.max = (centre + 0.5 * range).to(torch::kFloat32).contiguous();
  return n;
}

Normaliser Normaliser::fit(const torch::Tensor& train_features) {
  check_features(train_features);
  if (train_features.size(0) == 0) throw Error("normaliser", "no training samples to compute the ranges from");
  return from_extremes(std::get<0>(train_features.min(0)), std::get<0>(train_features.max(0)));
}

Normaliser Normaliser::fit(const torch::Tensor& features, const std::vector<int64_t>& rows,
                           const torch::Tensor& extra) {
  check_features(features);
  if (rows.empty()) throw Error("normaliser", "no training samples to compute the ranges from");
  const torch::Tensor index = torch::tensor(rows, torch::kInt64);
  TORCH_CHECK(index.min().item<int64_t>() >= 0 && index.max().item<int64_t>() < features.size(0),
              "normaliser: row index out of range");
  torch::Tensor lo, hi;
  constexpr int64_t kChunk = 256;  // bounds the copy of the selected rows
  for (int64_t begin = 0; begin < index.size(0); begin += kChunk) {
    const torch::Tensor chunk =
        features.index_select(0, index.slice(0, begin, std::min(begin + kChunk, index.size(0))));
    const torch::Tensor chunk_lo = std::get<0>(chunk.min(0)), chunk_hi = std::get<0>(chunk.max(0));
    lo = lo.defined() ? torch::minimum(lo, chunk_lo) : chunk_lo;
    hi = hi.defined() ? torch::maximum(hi, chunk_hi) : chunk_hi;
  }
  if (extra.defined() && extra.size(0) > 0) {
    check_features(extra);
    TORCH_CHECK(extra.size(1) == features.size(1), "normaliser: extra samples have another vertex count");
    lo = torch::minimum(lo, std::get<0>(extra.min(0)).to(lo.scalar_type()));
    hi = torch::maximum(hi, std::get<0>(extra.max(0)).to(hi.scalar_type()));
  }
  return from_extremes(lo, hi);
}

namespace {
// x viewed as [-1, V, 9], checked against the normaliser's V.
torch::Tensor as_vertices(const torch::Tensor& x, int64_t vertices, const char* what) {
  const int64_t width = vertices * kDrWidth;
  const bool shaped =
      (x.dim() >= 2 && x.size(-1) == kDrWidth && x.size(-2) == vertices) || (x.dim() >= 1 && x.size(-1) == width);
  TORCH_CHECK(shaped, what, ": expected [..., ", vertices, ", 9] or [..., ", width, "], got ", x.sizes());
  return x.reshape({-1, vertices, kDrWidth});
}
}  // namespace

torch::Tensor Normaliser::normalise(const torch::Tensor& x) const {
  TORCH_CHECK(min.defined(), "normalise: the normaliser is empty");
  const torch::Tensor lo = min.to(x.device(), x.scalar_type()), hi = max.to(x.device(), x.scalar_type());
  const torch::Tensor v = as_vertices(x, vertex_count(), "normalise");
  const torch::Tensor y = (v - lo) * (2 * kNormalisedBound / (hi - lo)) - kNormalisedBound;
  return y.reshape(x.sizes());
}

torch::Tensor Normaliser::normalise_within_range(const torch::Tensor& x) const {
  // Widened ranges are kMinimumRange up to the float32 rounding of min and max.
  const torch::Tensor constant = ((max - min) < 1.5 * kMinimumRange).to(x.device());
  const torch::Tensor y =
      as_vertices(normalise(x), vertex_count(), "normalise_within_range").clamp(-kNormalisedBound, kNormalisedBound);
  return torch::where(constant, torch::zeros({}, y.options()), y).reshape(x.sizes());
}

torch::Tensor Normaliser::denormalise(const torch::Tensor& y) const {
  TORCH_CHECK(min.defined(), "denormalise: the normaliser is empty");
  const torch::Tensor lo = min.to(y.device(), y.scalar_type()), hi = max.to(y.device(), y.scalar_type());
  const torch::Tensor v = as_vertices(y, vertex_count(), "denormalise");
  const torch::Tensor x = (v + kNormalisedBound) * ((hi - lo) / (2 * kNormalisedBound)) + lo;
  return x.reshape(y.sizes());
}

void Normaliser::save(const std::string& path) const {
  TORCH_CHECK(min.defined() && max.defined(), "Normaliser::save: the normaliser is empty");
  save_tensors(path, {{"min", min}, {"max", max}, {"bound", torch::tensor(kNormalisedBound, torch::kFloat64)}});
}

Normaliser Normaliser::load(const std::string& path) {
  const TensorMap tensors = load_tensors(path);
  Normaliser n;
  n.min = tensor_named(tensors, "min", path).to(torch::kFloat32).contiguous();
  n.max = tensor_named(tensors, "max", path).to(torch::kFloat32).contiguous();
  if (n.min.dim() != 2 || n.min.size(1) != kDrWidth || !n.min.sizes().equals(n.max.sizes()))
    throw Error(path, "expected min and max of shape [V, 9], got " + c10::str(n.min.sizes()) + " and " +
                          c10::str(n.max.sizes()));
  if (tensors.count("bound") && std::abs(tensors.at("bound").item<double>() - kNormalisedBound) > 1e-12)
    throw Error(path, "was written for the bound " + std::to_string(tensors.at("bound").item<double>()) +
                          " but this build normalises to " + std::to_string(kNormalisedBound));
  if ((n.max < n.min).any().item<bool>()) throw Error(path, "has a dimension with max < min");
  return n;
}

}  // namespace retarget
