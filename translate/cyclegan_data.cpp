#include "translate/cyclegan_data.h"

#include <fmt/format.h>

#include <algorithm>
#include <vector>

#include "core/error.h"
#include "core/log.h"
#include "core/parallel_for.h"
#include "core/progress.h"
#include "core/random.h"
#include "geometry/reconstruction.h"

namespace retarget {

namespace {

constexpr uint64_t kLightFieldSampleStream = 11;

torch::Tensor training_features(const Dataset& d) {
  return d.features.index_select(0, torch::tensor(d.train, torch::kInt64));
}

// Positions in d.train of the training samples to describe: `samples` of them drawn with
// `seed`, ascending.
std::vector<int64_t> sampled(const Dataset& d, int samples, uint64_t seed) {
  if (d.train.size() < 2)
    throw Error(d.folder,
                fmt::format("has {} training samples; the light-field pairs need at least 2", d.train.size()));
  std::vector<int64_t> order = Random(seed).permutation(static_cast<int64_t>(d.train.size()));
  order.resize(std::min(order.size(), static_cast<size_t>(samples)));
  std::sort(order.begin(), order.end());
  return order;
}

// [P, light_field_size] float32: the descriptor of the rebuilt mesh of each training sample at
// `positions` (in d.train).
torch::Tensor descriptors(const Dataset& d, const std::vector<int64_t>& positions, const LightFieldOptions& options,
                          Progress& progress) {
  ReconstructionOptions r;
  r.weighting = d.dr.weighting;
  r.align_to_rest = true;
  r.threads = 1;
  const Reconstruction rebuild(d.rest, r);
  const int width = light_field_size(options);
  torch::Tensor out = torch::zeros({static_cast<int64_t>(positions.size()), width}, torch::kFloat32);
  const torch::Tensor features = d.features.contiguous();
  parallel_for(static_cast<int>(positions.size()), [&](int i) {
    const torch::Tensor f = features[d.train[static_cast<size_t>(positions[static_cast<size_t>(i)])]].contiguous();
    const Eigen::VectorXf descriptor =
        light_field_descriptor(d.rest, rebuild.reconstruct(f.data_ptr<float>()), options);
    std::copy(descriptor.data(), descriptor.data() + width, out[i].data_ptr<float>());
    progress.advance();
  });
  return out;
}

}  // namespace

CycleGanCodes training_codes(TrainedVae& human, TrainedVae& avatar) {
  return {encoder_means(human, training_features(human.dataset)),
          encoder_means(avatar, training_features(avatar.dataset))};
}

LightFieldPairs light_field_pairs(const TrainedVae& human, const TrainedVae& avatar, const CycleGanCodes& codes,
                                  int samples, const LightFieldOptions& options, uint64_t seed,
                                  std::ostream* progress_out) {
  options.validate();
  const std::vector<int64_t> h = sampled(human.dataset, samples, mix_seed(seed, kLightFieldSampleStream, 0));
  const std::vector<int64_t> a = sampled(avatar.dataset, samples, mix_seed(seed, kLightFieldSampleStream, 1));
  Progress progress("light fields (meshes)", static_cast<int64_t>(h.size() + a.size()), progress_out);
  const torch::Tensor dh = descriptors(human.dataset, h, options, progress);
  const torch::Tensor da = descriptors(avatar.dataset, a, options, progress);
  progress.finish();

  LightFieldPairs pairs;
  pairs.human = codes.human.index_select(0, torch::tensor(h, torch::kInt64));
  pairs.avatar = codes.avatar.index_select(0, torch::tensor(a, torch::kInt64));
  const torch::Tensor raw = torch::cdist(dh.to(torch::kFloat64), da.to(torch::kFloat64), 1.0);
  pairs.raw_min = raw.min().item<double>();
  pairs.raw_max = raw.max().item<double>();
  if (!(pairs.raw_max > pairs.raw_min))
    throw Error(human.folder + ", " + avatar.folder,
                fmt::format("every human-avatar pair of the {} x {} sampled meshes lies at the same light-field "
                            "distance ({}); there is nothing to learn similarity from",
                            h.size(), a.size(), pairs.raw_min));
  pairs.distance = ((raw - pairs.raw_min) / (pairs.raw_max - pairs.raw_min)).to(torch::kFloat32);
  log::info(
      "light fields of {} human and {} avatar meshes ({} values each): pair distances {:.4g} .. {:.4g}, "
      "normalised mean {:.3f}",
      h.size(), a.size(), dh.size(1), pairs.raw_min, pairs.raw_max, pairs.distance.mean().item<double>());
  return pairs;
}

}  // namespace retarget
