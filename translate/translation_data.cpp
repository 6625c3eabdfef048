#include "translate/translation_data.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "annotate/annotation_store.h"
#include "core/error.h"
#include "core/log.h"
#include "core/random.h"
#include "correspond/annotation_project.h"
#include "data/dataset.h"
#include "train/train_config.h"

namespace retarget {

namespace fs = std::filesystem;

namespace {

// y0 re-encoded from the stored DT features by the avatar VAE must match the stored codes to
// this (float32 encoders on the same CPU agree to ~1e-6; another checkpoint differs by ~1e-2).
constexpr double kCodeTolerance = 1e-4;

std::string same_path_or_both(const std::string& a, const std::string& b) {
  std::error_code ec;
  const fs::path ca = fs::weakly_canonical(a, ec), cb = fs::weakly_canonical(b, ec);
  return ca == cb ? a : a + " (correspondences: " + b + ")";
}

std::string describe(const Triplet& t) {
  return fmt::format("triplet (group {} \"{}\", positive {}, negative {}{})", t.group, t.anchor, t.positive, t.negative,
                     t.derived ? ", derived" : "");
}

// Rows of `expression_of` ([N] int64) per expression k: rows_of[k].
std::vector<std::vector<int64_t>> rows_per_expression(const torch::Tensor& expression_of, int64_t k_count) {
  std::vector<std::vector<int64_t>> rows(static_cast<size_t>(k_count));
  const auto e = expression_of.accessor<int64_t, 1>();
  for (int64_t i = 0; i < expression_of.size(0); ++i) rows[static_cast<size_t>(e[i])].push_back(i);
  return rows;
}

// Triplets resolved to (k, p_positive, p_negative) within the groups.
struct ResolvedTriplet {
  int64_t k, positive, negative;
};

TripletCodes triplet_codes(const std::vector<ResolvedTriplet>& triplets,
                           const std::vector<std::vector<int64_t>>& inputs_of, const torch::Tensor& group_codes,
                           const torch::Tensor& group_spread) {
  std::vector<int64_t> anchor, k_of, p_of, n_of;
  std::vector<int64_t> offsets = {0};
  for (const ResolvedTriplet& t : triplets) {
    offsets.push_back(offsets.back() + static_cast<int64_t>(inputs_of[static_cast<size_t>(t.k)].size()));
    for (int64_t row : inputs_of[static_cast<size_t>(t.k)]) {
      anchor.push_back(row);
      k_of.push_back(t.k);
      p_of.push_back(t.positive);
      n_of.push_back(t.negative);
    }
  }
  const int64_t latent = group_codes.size(2);
  TripletCodes codes;
  codes.triplets = static_cast<int64_t>(triplets.size());
  codes.offsets = offsets;
  if (anchor.empty()) {
    codes.anchor = torch::zeros({0}, torch::kInt64);
    codes.positive = torch::zeros({0, latent});
    codes.negative = torch::zeros({0, latent});
    codes.group_scale = torch::zeros({0});
    return codes;
  }
  codes.anchor = torch::tensor(anchor, torch::kInt64);
  const torch::Tensor k = torch::tensor(k_of, torch::kInt64);
  const torch::Tensor flat = group_codes.reshape({-1, latent});  // row k * P + p
  const int64_t p_count = group_codes.size(1);
  codes.positive = flat.index_select(0, k * p_count + torch::tensor(p_of, torch::kInt64)).contiguous();
  codes.negative = flat.index_select(0, k * p_count + torch::tensor(n_of, torch::kInt64)).contiguous();
  codes.group_scale = group_spread.index_select(0, k).reciprocal().contiguous();
  return codes;
}

}  // namespace

TranslationData make_translation_data(TrainedVae& human, TrainedVae& avatar, const Correspondences& c,
                                      const std::vector<Triplet>& triplets, const std::string& triplets_source,
                                      HumanCodes codes, double held_out_fraction, uint64_t seed, const Dataset* faces) {
  if (human.dataset.kind != DatasetKind::human)
    throw Error(human.folder,
                "is a VAE run on an avatar dataset (" + human.dataset.folder + "); data.human_vae needs a human one");
  const Dataset& hd = faces ? *faces : human.dataset;
  if (hd.kind != DatasetKind::human)
    throw Error(hd.folder, "is an avatar dataset; data.human_dataset needs a human one");
  if (hd.fingerprint != human.dataset.fingerprint)
    throw Error(hd.folder, fmt::format("has faces of topology {}, the human VAE's ({}) {}: data.human_dataset needs "
                                       "the VAE's topology",
                                       hd.fingerprint, human.folder, human.dataset.fingerprint));
  if (avatar.dataset.kind != DatasetKind::avatar)
    throw Error(avatar.folder,
                "is a VAE run on a human dataset (" + avatar.dataset.folder + "); data.avatar_vae needs an avatar one");
  check_correspondences(c, hd, avatar.dataset);

  // The avatar VAE must be the encoder that made y0: re-encode what y0 was made from (the DT
  // results, or their projections onto the rig).
  const torch::Tensor y0_again = encoder_means(avatar, c.start_features(), /*clamp_to_range=*/true);
  if (y0_again.sizes() != c.y0.sizes())
    throw Error(avatar.folder, fmt::format("its codes have {} values, the correspondences in {} have {}",
                                           y0_again.size(1), c.folder, c.y0.size(1)));
  const double code_difference = (y0_again - c.y0).abs().max().item<double>();
  if (code_difference > kCodeTolerance)
    throw Error(same_path_or_both(avatar.folder, c.avatar_vae_run),
                fmt::format("its encoder ({} checkpoint) does not reproduce the codes y0 of the correspondences in {} "
                            "(max difference {:.3g}): they were built with another avatar VAE run or checkpoint, "
                            "or the run was retrained since; rebuild the correspondences with this run",
                            c.avatar_vae_checkpoint, c.folder, code_difference));

  TranslationData data;
  data.expressions = c.expressions;
  data.y0 = c.y0.to(torch::kFloat32).contiguous();
  data.group_codes = c.group_codes.to(torch::kFloat32).contiguous();
  data.group_spread = (data.group_codes - data.group_codes.mean(1, /*keepdim=*/true))
                          .pow(2)
                          .sum(2)
                          .mean(1)
                          .clamp_min(kMinGroupSpread)
                          .contiguous();
  data.human_fingerprint = hd.fingerprint;
  data.avatar_fingerprint = avatar.dataset.fingerprint;
  const int64_t k_count = c.expression_count();

  // Human expression index of each k.
  std::vector<int64_t> human_expression(static_cast<size_t>(k_count), -1);
  std::vector<int64_t> k_of_human(hd.expressions.size(), -1);
  for (int64_t k = 0; k < k_count; ++k) {
    const auto it = std::find(hd.expressions.begin(), hd.expressions.end(), c.expressions[static_cast<size_t>(k)]);
    if (it == hd.expressions.end())
      throw Error(hd.folder, fmt::format("has no expression \"{}\", which the correspondences in {} use",
                                         c.expressions[static_cast<size_t>(k)], c.folder));
    human_expression[static_cast<size_t>(k)] = it - hd.expressions.begin();
    k_of_human[static_cast<size_t>(it - hd.expressions.begin())] = k;
  }

  // Samples of the reference expressions among `rows` -> (raw features, k).
  auto samples = [&](const std::vector<int64_t>& rows, torch::Tensor& x, torch::Tensor& k) {
    std::vector<int64_t> kept, ks;
    const auto e = hd.expression.accessor<int64_t, 1>();
    for (int64_t row : rows) {
      const int64_t k_row = k_of_human[static_cast<size_t>(e[row])];
      if (k_row < 0) continue;
      kept.push_back(row);
      ks.push_back(k_row);
    }
    if (kept.empty()) {
      x = torch::zeros({0, human.vae->options.latent()});
      k = torch::zeros({0}, torch::kInt64);
      return;
    }
    x = encoder_means(human, hd.features.index_select(0, torch::tensor(kept, torch::kInt64)));
    k = torch::tensor(ks, torch::kInt64);
  };
  if (codes == HumanCodes::subjects) {
    samples(hd.train, data.inputs, data.input_expression);
    if (data.inputs.size(0) == 0)
      throw Error(hd.folder, "has no training samples of the correspondences' expressions; use human_codes: targets");
  } else {
    data.inputs = encoder_means(human, hd.targets.index_select(0, torch::tensor(human_expression, torch::kInt64)));
    data.input_expression = torch::arange(k_count, torch::kInt64);
  }
  samples(hd.test, data.test_inputs, data.test_expression);

  // Triplets -> positions in the groups.
  std::vector<ResolvedTriplet> resolved;
  resolved.reserve(triplets.size());
  const auto groups = c.groups.accessor<int64_t, 2>();
  for (const Triplet& t : triplets) {
    const auto it = std::find(c.expressions.begin(), c.expressions.end(), t.anchor);
    if (it == c.expressions.end())
      throw Error(triplets_source, fmt::format("{}: the correspondences in {} have no expression \"{}\" (is the "
                                               "annotation project made from other correspondences?)",
                                               describe(t), c.folder, t.anchor));
    const int64_t k = it - c.expressions.begin();
    auto position = [&](int64_t sample) {
      for (int64_t p = 0; p < c.groups.size(1); ++p)
        if (groups[k][p] == sample) return p;
      throw Error(triplets_source, fmt::format("{}: avatar sample {} is not in the group of \"{}\" in the "
                                               "correspondences in {} (is the annotation project made from other "
                                               "correspondences?)",
                                               describe(t), sample, t.anchor, c.folder));
    };
    resolved.push_back({k, position(t.positive), position(t.negative)});
  }
  data.triplets_loaded = static_cast<int64_t>(resolved.size());

  // Seeded split: a share of the triplets is never trained on.
  std::vector<size_t> order(resolved.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  Random(mix_seed(seed, 1)).shuffle(order);
  int64_t held = std::llround(held_out_fraction * static_cast<double>(order.size()));
  if (held_out_fraction > 0 && order.size() >= 2) held = std::clamp<int64_t>(held, 1, order.size() - 1);
  std::vector<size_t> held_rows(order.begin(), order.begin() + held), train_rows(order.begin() + held, order.end());
  std::sort(held_rows.begin(), held_rows.end());
  std::sort(train_rows.begin(), train_rows.end());
  std::vector<ResolvedTriplet> train_triplets, held_triplets;
  for (size_t i : train_rows) train_triplets.push_back(resolved[i]);
  for (size_t i : held_rows) held_triplets.push_back(resolved[i]);
  const auto inputs_of = rows_per_expression(data.input_expression, k_count);
  data.train_triplets = triplet_codes(train_triplets, inputs_of, data.group_codes, data.group_spread);
  data.held_out_triplets = triplet_codes(held_triplets, inputs_of, data.group_codes, data.group_spread);
  return data;
}

TranslationData load_translation_data(const TranslationDataOptions& options, uint64_t seed) {
  const Correspondences c = load_correspondences(options.correspondences);
  TrainedVae human = load_trained_vae(options.human_vae, options.human_checkpoint);
  TrainedVae avatar = load_trained_vae(options.avatar_vae, c.avatar_vae_checkpoint);
  std::vector<Triplet> triplets;
  if (!options.triplets.empty()) triplets = load_project_triplets(options.triplets, options.include_derived);
  if (!options.triplets.empty() && triplets.empty())
    log::warn("{}: no triplets yet (annotate first); training without L_T", options.triplets);
  if (options.human_dataset.empty())
    return make_translation_data(human, avatar, c, triplets, options.triplets, options.human_codes,
                                 options.held_out_fraction, seed);
  const Dataset faces = load_dataset(options.human_dataset);
  return make_translation_data(human, avatar, c, triplets, options.triplets, options.human_codes,
                               options.held_out_fraction, seed, &faces);
}

}  // namespace retarget
