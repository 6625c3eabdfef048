#include "translate/translation_trainer.h"

#include <ATen/CPUGeneratorImpl.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <tuple>

#include "core/error.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/random.h"
#include "core/timer.h"
#include "models/losses.h"
#include "models/translation_mlp.h"
#include "train/checkpoint.h"
#include "train/run_lifecycle.h"
#include "train/train_config.h"
#include "translate/translation_data.h"

namespace retarget {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Seed streams (core/random.h mix_seed); 1 is the triplet split (translation_data.cpp).
constexpr uint64_t kInitStream = 2, kInputOrderStream = 4, kTripletOrderStream = 5, kTripletAnchorStream = 6,
                   kInputNoiseStream = 7;

// Per code dimension, the root mean square over the inputs of (x - the mean of x's
// expression's inputs): [Lh] float32 (0 where every expression has one input).
torch::Tensor within_expression_spread(const TranslationData& d) {
  const int64_t k = static_cast<int64_t>(d.expressions.size());
  torch::Tensor sum = torch::zeros({k, d.latent_in()}, torch::kFloat64);
  torch::Tensor count = torch::zeros({k, 1}, torch::kFloat64);
  sum.index_add_(0, d.input_expression, d.inputs.to(torch::kFloat64));
  count.index_add_(0, d.input_expression, torch::ones({d.inputs.size(0), 1}, torch::kFloat64));
  const torch::Tensor mean = sum / count.clamp_min(1);
  const torch::Tensor residual = d.inputs.to(torch::kFloat64) - mean.index_select(0, d.input_expression);
  return residual.pow(2).mean(0).sqrt().to(torch::kFloat32);
}

// The inputs of `rows`, each with N(0, noise^2) added per dimension (noise: [Lh], undefined = none).
torch::Tensor noisy_inputs(const TranslationData& d, const torch::Tensor& rows, const torch::Tensor& noise,
                           at::Generator& generator) {
  torch::Tensor x = d.inputs.index_select(0, rows);
  if (!noise.defined()) return x;
  return x + torch::randn(x.sizes(), generator, x.options()) * noise;
}

std::unique_ptr<torch::optim::Adam> new_adam(TranslationMlpImpl& f, double lr) {
  return std::make_unique<torch::optim::Adam>(f.parameters(), torch::optim::AdamOptions(lr));
}

void set_lr(torch::optim::Optimizer& optimiser, double lr) {
  for (auto& group : optimiser.param_groups()) static_cast<torch::optim::AdamOptions&>(group.options()).lr(lr);
}

torch::Tensor slice_of(const std::vector<int64_t>& order, int64_t begin, int64_t end) {
  return torch::tensor(std::vector<int64_t>(order.begin() + begin, order.begin() + end), torch::kInt64);
}

// Losses of one batch: inputs `rows` and triplet rows `triplet_rows` (may be empty).
struct BatchLoss {
  torch::Tensor paired, group, triplet;
};

// The per-row unit of the triplet distances: the groups' spreads, or the paper's absolute ones.
torch::Tensor triplet_scale(const TripletCodes& t, TripletScale scale) {
  return scale == TripletScale::group ? t.group_scale : torch::Tensor();
}

// This rank's part [first, second) of n rows, and its share of them (1 in one process).
struct Part {
  int64_t first = 0, last = 0;
  double share = 1;
  bool empty() const { return last <= first; }
};

Part part_of(DataParallel* parallel, int64_t n) {
  Part p{0, n, 1};
  if (parallel && n > 0) {
    std::tie(p.first, p.last) = parallel->shard(0, n);
    p.share = static_cast<double>(p.last - p.first) / static_cast<double>(n);
  }
  return p;
}

// noise: input noise per code dimension, undefined = none (noisy_inputs). Data-parallel, the
// whole batch's noise is drawn on every rank (so the draws are one process's) and each rank
// scores its part of the inputs and of the triplets, each term scaled by its share: the ranks'
// gradients sum to the whole batch's.
BatchLoss batch_loss(TranslationMlpImpl& f, const TranslationData& d, const TripletCodes& t, const torch::Tensor& rows,
                     const torch::Tensor& triplet_rows, double margin, TripletScale scale, const torch::Tensor& noise,
                     at::Generator& generator, DataParallel* parallel) {
  BatchLoss loss;
  loss.paired = loss.group = loss.triplet = torch::zeros({});
  const torch::Tensor inputs = noisy_inputs(d, rows, noise, generator);
  const Part p = part_of(parallel, rows.numel());
  if (!p.empty()) {
    const torch::Tensor k = d.input_expression.index_select(0, rows.slice(0, p.first, p.last));
    const torch::Tensor out = f.forward(inputs.slice(0, p.first, p.last));
    loss.paired = p.share * paired_loss(out, d.y0.index_select(0, k));
    loss.group = p.share * group_loss(out, d.group_codes.index_select(0, k));
  }
  if (triplet_rows.numel() > 0) {
    const torch::Tensor anchors = noisy_inputs(d, t.anchor.index_select(0, triplet_rows), noise, generator);
    const Part q = part_of(parallel, triplet_rows.numel());
    if (!q.empty()) {
      const torch::Tensor mine = triplet_rows.slice(0, q.first, q.last);
      const torch::Tensor anchor = f.forward(anchors.slice(0, q.first, q.last));
      const torch::Tensor unit = triplet_scale(t, scale);
      loss.triplet = q.share * triplet_loss(anchor, t.positive.index_select(0, mine), t.negative.index_select(0, mine),
                                            margin, unit.defined() ? unit.index_select(0, mine) : unit);
    }
  }
  return loss;
}

// The logged metrics of F as it stands, over the whole data (no gradients).
TranslationEpochMetrics evaluate(TranslationMlpImpl& f, const TranslationData& d, double margin, TripletScale scale,
                                 const LossWeights& w) {
  torch::NoGradGuard no_grad;
  TranslationEpochMetrics m;
  const torch::Tensor out = f.forward(d.inputs);
  m.paired = paired_loss(out, d.y0.index_select(0, d.input_expression)).item<double>();
  m.group = group_loss(out, d.group_codes.index_select(0, d.input_expression)).item<double>();
  auto triplets = [&](const TripletCodes& t, double& loss, double& accuracy) {
    if (t.rows() == 0) {
      loss = 0;
      accuracy = kNaN;
      return;
    }
    const torch::Tensor anchor = out.index_select(0, t.anchor);
    loss = triplet_loss(anchor, t.positive, t.negative, margin, triplet_scale(t, scale)).item<double>();
    accuracy = triplet_accuracy(anchor, t.positive, t.negative);
  };
  triplets(d.train_triplets, m.triplet, m.train_accuracy);
  triplets(d.held_out_triplets, m.held_out_triplet, m.held_out_accuracy);
  if (d.held_out_triplets.rows() == 0) m.held_out_triplet = kNaN;
  m.test_paired = d.test_inputs.size(0) > 0
                      ? paired_loss(f.forward(d.test_inputs), d.y0.index_select(0, d.test_expression)).item<double>()
                      : kNaN;
  m.loss = w.paired * m.paired + w.group * m.group + w.triplet * m.triplet;
  return m;
}

std::string accuracy_text(double accuracy) {
  return std::isfinite(accuracy) ? fmt::format("{:.1f}%", 100 * accuracy) : "-";
}

}  // namespace

namespace {

// The input noise's scale per code dimension (config.training.input_noise x the codes' spread
// about their expression's mean); undefined: none.
torch::Tensor input_noise(const TranslationData& data, const TranslationTrainConfig& config) {
  torch::Tensor noise;
  if (config.training.input_noise > 0) {
    const torch::Tensor spread = within_expression_spread(data);
    log::info("input noise: {} x the codes' spread about their expression's mean (median over dimensions {:.3g})",
              config.training.input_noise, spread.median().item<double>());
    if (spread.max().item<double>() > 0)
      noise = config.training.input_noise * spread;
    else
      log::warn(
          "input noise: every expression has one input code (human_codes: targets), so there is no spread "
          "to add; training without noise");
  }
  return noise;
}

// Each training triplet once, anchored on one input of its expression drawn for epoch `e`: rows
// of `triplets` in the epoch's order.
std::vector<int64_t> epoch_triplet_order(const TripletCodes& triplets, uint64_t seed, uint64_t e) {
  std::vector<int64_t> triplet_order;
  Random anchor(mix_seed(seed, kTripletAnchorStream, e));
  for (int64_t t : Random(mix_seed(seed, kTripletOrderStream, e)).permutation(triplets.triplets)) {
    const int64_t first = triplets.offsets[static_cast<size_t>(t)];
    const int64_t count = triplets.offsets[static_cast<size_t>(t) + 1] - first;
    if (count > 0) triplet_order.push_back(first + static_cast<int64_t>(anchor.below(static_cast<uint64_t>(count))));
  }
  return triplet_order;
}

}  // namespace

TranslationTrainSummary train_translation(const TranslationTrainConfig& requested,
                                          const TranslationTrainOptions& options) {
  Stopwatch clock;
  RunFolder run = open_run(requested.output, "translation", to_yaml(requested), options.start, options.parallel.get());
  const TranslationTrainConfig config = config_of_run(run, options.start, requested, read_translation_train_config);
  const int threads = use_training_threads(config.training.threads);
  const uint64_t seed = config.training.seed;

  const TranslationData data = load_translation_data(config.data, seed);
  record_fingerprint(run, "human_dataset", data.human_fingerprint, "human dataset", run.folder());
  record_fingerprint(run, "avatar_dataset", data.avatar_fingerprint, "avatar dataset", run.folder());
  const int total_epochs = config.total_epochs();

  torch::manual_seed(mix_seed(seed, kInitStream));
  TranslationMlpOptions model = config.model;
  model.latent_in(data.latent_in()).latent_out(data.latent_out());
  TranslationMlp f(model);
  std::unique_ptr<torch::optim::Adam> optimiser = new_adam(*f, config.stages.front().lr);
  CheckpointState state = resume_run(run, total_epochs, [&](const std::string& path) {
    return load_checkpoint(path, *f, optimiser.get(), "translation");
  });
  mark_running(run);

  // Stage snapshots due once `done` epochs are complete (every stage ending there, 0-epoch
  // stages included).
  auto write_stage_snapshots = [&](int done) {
    for (size_t s = 0; s < config.stages.size(); ++s)
      if (config.stage_end(static_cast<int>(s)) == done)
        if (run.writes())
          save_checkpoint(run.checkpoint_path(fmt::format("stage{}", s + 1)), *f, nullptr, {done, -1, 0});
  };
  if (state.epoch == 0) write_stage_snapshots(0);

  const int64_t n = data.inputs.size(0);
  const int64_t batch = config.training.batch_size;
  const int64_t steps = (n + batch - 1) / batch;
  const TripletCodes& triplets = data.train_triplets;
  log::info(
      "training F ({} -> {} codes, hidden {}) on {} expressions: {} inputs ({} codes), {} training and {} held-out "
      "triplets ({} and {} rows), batch {}, {} stages, {} epochs, {} threads -> {}",
      data.latent_in(), data.latent_out(), model.hidden(), data.expressions.size(), n,
      to_string(config.data.human_codes), triplets.triplets, data.held_out_triplets.triplets, triplets.rows(),
      data.held_out_triplets.rows(), batch, config.stages.size(), total_epochs, threads, run.folder());
  log::info(
      "code space: median group spread {:.3g} (mean squared distance of a group's codes to their centroid), "
      "median squared distance of y0 to its group's centroid {:.3g}; triplet margin {} in {}",
      data.group_spread.median().item<double>(),
      (data.y0 - data.group_codes.mean(1)).pow(2).sum(1).median().item<double>(), config.margin,
      config.triplet_scale == TripletScale::group ? "units of each group's spread" : "squared code units");

  const torch::Tensor noise = input_noise(data, config);  // per code dimension; undefined: none

  TranslationTrainSummary summary;
  summary.folder = run.folder();
  summary.inputs = n;
  summary.expressions = static_cast<int64_t>(data.expressions.size());
  summary.test_inputs = data.test_inputs.size(0);
  summary.triplets = data.triplets_loaded;
  summary.train_triplets = triplets.triplets;
  summary.held_out_triplets = data.held_out_triplets.triplets;

  if (options.parallel) options.parallel->warn_if_batch_too_small(config.training.batch_size, "training.batch_size");
  std::unique_ptr<GradientSync> sync;  // the ranks' gradients summed while backward runs
  if (options.parallel) sync = std::make_unique<GradientSync>(*options.parallel, f->parameters());
  Progress progress("training F (epochs)", total_epochs - state.epoch, options.progress);
  f->train();
  for (int epoch = state.epoch; epoch < total_epochs; ++epoch) {
    if (options.stop_after_epochs >= 0 && summary.epochs_run >= options.stop_after_epochs) break;
    Stopwatch epoch_clock;
    const int s = config.stage_of(epoch);
    const StageOptions& stage = config.stages[static_cast<size_t>(s)];
    const int stage_start = config.stage_end(s) - stage.epochs;
    if (epoch == stage_start) {
      optimiser = new_adam(*f, stage.lr);  // a fresh Adam per stage (see the header)
      log::info("stage {} ({}): {} epochs, lr {:.3g}, weights paired {:.3g}, group {:.3g}, triplet {:.3g}", s + 1,
                stage.name, stage.epochs, stage.lr, stage.weights.paired, stage.weights.group, stage.weights.triplet);
    }
    set_lr(*optimiser, stage.lr);

    const auto e = static_cast<uint64_t>(epoch);
    const std::vector<int64_t> order = Random(mix_seed(seed, kInputOrderStream, e)).permutation(n);
    const std::vector<int64_t> triplet_order = epoch_triplet_order(triplets, seed, e);
    const auto t_count = static_cast<int64_t>(triplet_order.size());
    at::Generator generator = at::make_generator<at::CPUGeneratorImpl>(mix_seed(seed, kInputNoiseStream, e));
    for (int64_t step = 0; step < steps; ++step) {
      const torch::Tensor rows = slice_of(order, step * batch, std::min(n, (step + 1) * batch));
      const torch::Tensor triplet_rows = slice_of(triplet_order, step * t_count / steps, (step + 1) * t_count / steps);
      const BatchLoss loss = batch_loss(*f, data, triplets, rows, triplet_rows, config.margin, config.triplet_scale,
                                        noise, generator, options.parallel.get());
      const torch::Tensor total =
          stage.weights.paired * loss.paired + stage.weights.group * loss.group + stage.weights.triplet * loss.triplet;
      optimiser->zero_grad();
      if (total.requires_grad()) total.backward();
      if (sync) sync->finish();
      optimiser->step();
    }

    TranslationEpochMetrics m = evaluate(*f, data, config.margin, config.triplet_scale, stage.weights);
    const int done = epoch + 1;
    m.epoch = done;
    m.stage = s + 1;
    m.lr = stage.lr;
    if (!std::isfinite(m.loss))
      throw Error(run.folder(), fmt::format("the loss became {} in epoch {} (stage {}); lower stages[{}].lr (now {})",
                                            m.loss, done, s + 1, s, stage.lr));
    const double seconds = epoch_clock.seconds();
    run.append_metrics({{"epoch", done},
                        {"stage", s + 1},
                        {"lr", stage.lr},
                        {"weight_paired", stage.weights.paired},
                        {"weight_group", stage.weights.group},
                        {"weight_triplet", stage.weights.triplet},
                        {"loss", m.loss},
                        {"paired", m.paired},
                        {"group", m.group},
                        {"triplet", m.triplet},
                        {"train_accuracy", m.train_accuracy},
                        {"held_out_triplet", m.held_out_triplet},
                        {"held_out_accuracy", m.held_out_accuracy},
                        {"test_paired", m.test_paired},
                        {"seconds", seconds}});
    state.epoch = done;
    const bool stage_ends = done == config.stage_end(s);
    if (run.writes() && (done % config.training.checkpoint_every == 0 || stage_ends)) {
      save_checkpoint(run.last_checkpoint(), *f, optimiser.get(), state);
      if (stage_ends) write_stage_snapshots(done);
      record_checkpoint(run, state);
    }
    if (summary.epochs_run == 0) summary.first = m;
    summary.last = m;
    ++summary.epochs_run;
    progress.advance();
    const int report_every = std::max(1, stage.epochs / 10);
    if (stage_ends || (done - stage_start) % report_every == 0) {
      log::info(
          "epoch {}/{} (stage {} {}): loss {:.5g} (L_P {:.5g}, L_G {:.5g}, L_T {:.5g}), triplets right {} train, "
          "{} held out, test L_P {:.5g}",
          done, total_epochs, s + 1, stage.name, m.loss, m.paired, m.group, m.triplet, accuracy_text(m.train_accuracy),
          accuracy_text(m.held_out_accuracy), m.test_paired);
    }
    if (stage_ends) summary.stages.push_back({stage.name, stage.epochs, m});
  }
  progress.finish();
  summary.epochs_done = state.epoch;
  summary.finished = state.epoch >= total_epochs;
  if (summary.finished) finish_run(run, state);
  summary.seconds = clock.seconds();
  return summary;
}

}  // namespace retarget
