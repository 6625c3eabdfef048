#include "train/vae_trainer.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <set>

#include "core/error.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/random.h"
#include "core/timer.h"
#include "data/dataset.h"
#include "models/losses.h"
#include "train/principal_decoder.h"
#include "train/principal_encoder.h"
#include "train/run_lifecycle.h"
#include "train/train_config.h"
#include "train/vae_run.h"

namespace retarget {

namespace {

constexpr int64_t kEvalBatch = 64;

// Seed streams (core/random.h mix_seed): the validation split, the initial weights, LibTorch's
// generator in an epoch (the VAE's sampling) and the epoch's batch order.
constexpr uint64_t kValidationStream = 1, kInitStream = 2, kEpochTorchStream = 3, kEpochOrderStream = 4;

// Inputs and targets of the VAE, normalised, and the split.
struct TrainingData {
  torch::Tensor inputs;      // [N, V, 9]
  torch::Tensor targets;     // avatars: undefined (target = input); humans: [E, V, 9]
  torch::Tensor expression;  // humans: [N] int64
  std::vector<int64_t> train, validation;

  torch::Tensor targets_of(const torch::Tensor& rows, const torch::Tensor& x) const {
    return targets.defined() ? targets.index_select(0, expression.index_select(0, rows)) : x;
  }
};

// out: the normaliser of what the decoder produces (decoder_normaliser, train/vae_run.h).
TrainingData prepare(const Dataset& d, const Normaliser& out, double validation_fraction, uint64_t seed) {
  TrainingData data;
  data.inputs = d.normaliser.normalise(d.features).to(torch::kFloat32).contiguous();
  Random random(mix_seed(seed, kValidationStream));
  if (d.kind == DatasetKind::human) {
    data.targets = out.normalise(d.targets).to(torch::kFloat32).contiguous();
    data.expression = d.expression;
    std::vector<std::string> subjects = d.train_subjects;
    random.shuffle(subjects);
    int64_t held = std::llround(validation_fraction * static_cast<double>(subjects.size()));
    if (validation_fraction > 0 && subjects.size() >= 2) held = std::clamp<int64_t>(held, 1, subjects.size() - 1);
    const std::set<std::string> validation_subjects(subjects.begin(), subjects.begin() + held);
    const auto subject = d.subject.accessor<int64_t, 1>();
    for (int64_t row : d.train) {
      const bool held_out = validation_subjects.count(d.subjects[static_cast<size_t>(subject[row])]) > 0;
      (held_out ? data.validation : data.train).push_back(row);
    }
  } else {
    std::vector<int64_t> rows = d.train;
    random.shuffle(rows);
    int64_t held = std::llround(validation_fraction * static_cast<double>(rows.size()));
    if (validation_fraction > 0 && rows.size() >= 2) held = std::clamp<int64_t>(held, 1, rows.size() - 1);
    data.validation.assign(rows.begin(), rows.begin() + held);
    data.train.assign(rows.begin() + held, rows.end());
    std::sort(data.validation.begin(), data.validation.end());
    std::sort(data.train.begin(), data.train.end());
  }
  if (data.train.empty()) throw Error(d.folder, "has no training samples");
  return data;
}

torch::Tensor rows_tensor(const std::vector<int64_t>& rows, size_t begin, size_t end) {
  return torch::from_blob(const_cast<int64_t*>(rows.data() + begin), {static_cast<int64_t>(end - begin)}, torch::kInt64)
      .clone();
}

// Mean L1 between predict(x) (x: normalised inputs [B, V, 9]; returns [B, V, 9] or [V, 9] for
// one answer for every sample) and the normalised targets over `rows`: the validation loss of
// the VAE and of the trivial answers alike. NaN for no rows.
template <typename Predict>
double mean_l1(const TrainingData& data, const std::vector<int64_t>& rows, Predict predict) {
  if (rows.empty()) return std::numeric_limits<double>::quiet_NaN();
  torch::NoGradGuard no_grad;
  double sum = 0;
  int64_t count = 0;
  for (size_t begin = 0; begin < rows.size(); begin += kEvalBatch) {
    const size_t end = std::min(rows.size(), begin + static_cast<size_t>(kEvalBatch));
    const torch::Tensor idx = rows_tensor(rows, begin, end);
    const torch::Tensor x = data.inputs.index_select(0, idx);
    const torch::Tensor target = data.targets_of(idx, x);
    const torch::Tensor predicted = predict(x);
    sum += (predicted - target).abs().sum().item<double>();
    count += target.numel();
  }
  return sum / static_cast<double>(count);
}

// Mean L1 of the reconstructions from the codes' means (no sampling).
double validation_l1(MeshVaeImpl& vae, const TrainingData& data, const std::vector<int64_t>& rows) {
  vae.eval();
  const double l1 = mean_l1(data, rows, [&](const torch::Tensor& x) { return vae.forward(x, false).reconstruction; });
  vae.train();
  return l1;
}

// The trivial answers' L1 over `rows` (see the header): "neutral" and "mean".
std::map<std::string, double> trivial_l1(const Dataset& d, const Normaliser& out, const TrainingData& data,
                                         const std::vector<int64_t>& rows) {
  torch::NoGradGuard no_grad;
  const torch::Tensor neutral = out.normalise(torch::zeros({d.vertex_count(), 9}, torch::kFloat32)).to(torch::kFloat32);
  torch::Tensor sum = torch::zeros({d.vertex_count(), 9}, torch::kFloat64);
  for (size_t begin = 0; begin < data.train.size(); begin += kEvalBatch) {
    const size_t end = std::min(data.train.size(), begin + static_cast<size_t>(kEvalBatch));
    const torch::Tensor idx = rows_tensor(data.train, begin, end);
    sum += data.targets_of(idx, data.inputs.index_select(0, idx)).to(torch::kFloat64).sum(0);
  }
  const torch::Tensor mean = (sum / static_cast<double>(data.train.size())).to(torch::kFloat32);
  return {{"neutral", mean_l1(data, rows, [&](const torch::Tensor&) { return neutral; })},
          {"mean", mean_l1(data, rows, [&](const torch::Tensor&) { return mean; })}};
}

// The better (lower) trivial answer: name and L1; {"", NaN} when there is none.
std::pair<std::string, double> best_baseline(const std::map<std::string, double>& baselines) {
  std::pair<std::string, double> best{"", std::numeric_limits<double>::quiet_NaN()};
  for (const auto& [name, value] : baselines)
    if (std::isfinite(value) && !(value >= best.second)) best = {name, value};
  return best;
}

std::string versus_baseline(double l1, const std::map<std::string, double>& baselines) {
  const auto [name, value] = best_baseline(baselines);
  if (name.empty()) return "";
  return fmt::format(" ({} answer {:.5f}: x{:.2f})", name, value, value > 0 ? l1 / value : std::nan(""));
}

}  // namespace

std::vector<std::string> vae_training_warnings(double best_validation, int best_epoch, int epochs_done,
                                               int epochs_planned, const std::map<std::string, double>& baselines,
                                               const std::string& loss_name) {
  std::vector<std::string> warnings;
  const auto [name, value] = best_baseline(baselines);
  if (!name.empty() && best_epoch >= 0 && !(best_validation < 0.9 * value))
    warnings.push_back(fmt::format("does not beat the trivial answer: {} {:.5f} vs {} {:.5f} (x{:.2f})", loss_name,
                                   best_validation, name, value, value > 0 ? best_validation / value : std::nan("")));
  if (best_epoch >= 0 && epochs_done >= 8 &&
      static_cast<double>(best_epoch) <= std::max(2.0, 0.25 * static_cast<double>(epochs_planned)))
    warnings.push_back(fmt::format("stopped improving after epoch {} of {}{}", best_epoch, epochs_done,
                                   best_epoch == 0 ? " (no epoch beat the principal start)" : ""));
  return warnings;
}

std::string trivial_answer_advice(ReconstructionLoss loss) {
  return loss == ReconstructionLoss::l1
             ? "an L1 VAE can settle on the neutral face, where most samples of each region rest (each channel's "
               "median): try loss.reconstruction: squared"
             : "trained on the squared error, it is judged here in feature L1, where the neutral's per-channel "
               "medians are hard to beat: `retarget eval vae` scores it in mm beside the neutral answer";
}

namespace {

Dataset load_training_dataset(const VaeTrainConfig& config) {
  try {
    return load_dataset(config.data.dataset);
  } catch (const Error& e) {  // say which config key named the folder
    if (config.data.dataset_where.empty()) throw;
    throw Error(config.data.dataset_where, e.what());
  }
}

MeshVae build_vae(const Dataset& dataset, const VaeTrainConfig& config) {
  try {
    return build_mesh_vae(dataset.rest, config.model);
  } catch (const Error& e) {  // the widths' bounds for this dataset's vertex count
    throw Error(config.source + ": " + e.where(), e.detail());
  }
}

// The decoder started at the training targets' principal components (and the encoder skip, if
// any, at their codes).
void start_at_principal_components(MeshVaeImpl& vae, const TrainingData& data) {
  Stopwatch start_clock;
  std::vector<int64_t> rows = data.train;  // humans: each training row's identity-averaged target
  if (data.targets.defined()) {
    const auto expression = data.expression.accessor<int64_t, 1>();
    for (int64_t& row : rows) row = expression[row];
  }
  const PrincipalDecoderStart start =
      start_decoder_at_principal_components(vae, data.targets.defined() ? data.targets : data.inputs, rows);
  log::info(
      "decoder started at the training targets' {} leading principal components ({:.1f}% of their variance), "
      "{:.1f}s",
      start.components, 100 * start.explained, start_clock.seconds());
  if (!vae.encoder_skip.is_empty() && start.components > 0) {
    Stopwatch skip_clock;
    std::vector<int64_t> inputs(start.positions.size());  // the input row of each target row used
    for (size_t j = 0; j < inputs.size(); ++j) inputs[j] = data.train[start.positions[j]];
    const PrincipalEncoderStart skip = start_encoder_at_principal_codes(vae, data.inputs, inputs, start.codes);
    log::info("encoder skip started at their codes by ridge regression (residual {:.4f} of the codes' spread), {:.1f}s",
              skip.fit, skip_clock.seconds());
  }
}

// One epoch's training loss and its terms, averaged over its samples.
struct EpochLosses {
  double total = 0, recon = 0, kl = 0;  // recon: the training loss's reconstruction term
};

// One pass over `order` (the epoch's shuffled training rows) in batches. Data-parallel, each
// rank takes its shard of every batch with its rows of the batch's sampling noise, scales its
// loss by its share of the rows, and the ranks' gradients are summed before the step: every rank
// steps with the whole batch's gradient. The losses are summed over the ranks.
EpochLosses train_epoch(MeshVaeImpl& vae, torch::optim::Adam& optimiser, const TrainingData& data,
                        const VaeTrainConfig& config, const std::vector<int64_t>& order, Progress& progress,
                        DataParallel* parallel, GradientSync* sync) {
  const auto batch = static_cast<int64_t>(config.training.batch_size);
  const auto n = static_cast<int64_t>(order.size());
  EpochLosses l;
  for (int64_t begin = 0; begin < n; begin += batch) {
    const int64_t end = std::min(n, begin + batch);
    const torch::Tensor noise = torch::randn({end - begin, vae.options.latent()});  // every rank draws the batch's
    const auto [first, last] = parallel ? parallel->shard(begin, end) : std::pair<int64_t, int64_t>{begin, end};
    optimiser.zero_grad();
    if (last > first) {
      const torch::Tensor idx = rows_tensor(order, static_cast<size_t>(first), static_cast<size_t>(last));
      const torch::Tensor x = data.inputs.index_select(0, idx);
      const VaeOutput out = vae.forward_with_noise(x, noise.slice(0, first - begin, last - begin));
      const VaeLoss loss = vae_loss(out.reconstruction, data.targets_of(idx, x), out.mean, out.logvar, config.kl_weight,
                                    config.reconstruction);
      const auto rows = static_cast<double>(last - first);
      (loss.total * (rows / static_cast<double>(end - begin))).backward();
      l.total += loss.total.item<double>() * rows;
      l.recon += loss.reconstruction.item<double>() * rows;
      l.kl += loss.kl.item<double>() * rows;
    }
    if (sync) sync->finish();
    optimiser.step();
    progress.advance(end - begin);
  }
  progress.finish();
  if (parallel) {
    const std::vector<double> sums = parallel->sum({l.total, l.recon, l.kl});
    l = {sums[0], sums[1], sums[2]};
  }
  const auto count = static_cast<double>(n);
  l.total /= count;
  l.recon /= count;
  l.kl /= count;
  return l;
}

// What one training run works with, across its epochs.
struct VaeRun {
  const VaeTrainConfig& config;
  const VaeTrainOptions& options;
  RunFolder& run;
  const TrainingData& data;
  MeshVae& vae;
  torch::optim::Adam& optimiser;
  const std::map<std::string, double>& baselines;
  CheckpointState& state;
  VaeTrainSummary& summary;
  GradientSync* sync;  // data-parallel: the ranks' gradients summed while backward runs; null: one process
  double training_seconds = 0;
  int64_t samples_trained = 0;

  void epoch(int epoch) {
    Stopwatch epoch_clock;
    const double lr = config.schedule.lr_at(config.optimiser.lr, epoch);
    for (auto& group : optimiser.param_groups()) static_cast<torch::optim::AdamOptions&>(group.options()).lr(lr);
    torch::manual_seed(mix_seed(config.training.seed, kEpochTorchStream, static_cast<uint64_t>(epoch)));
    const std::vector<int64_t> order =
        Random(mix_seed(config.training.seed, kEpochOrderStream, static_cast<uint64_t>(epoch))).shuffled(data.train);
    Progress progress(fmt::format("epoch {}/{}", epoch + 1, config.training.epochs), static_cast<int64_t>(order.size()),
                      options.progress);
    const EpochLosses l = train_epoch(*vae, optimiser, data, config, order, progress, options.parallel.get(), sync);
    const double seconds = epoch_clock.seconds();
    training_seconds += seconds;
    samples_trained += static_cast<int64_t>(order.size());
    if (!std::isfinite(l.total))
      throw Error(run.folder(), fmt::format("the loss became {} in epoch {}; lower optimiser.lr (now {})", l.total,
                                            epoch + 1, config.optimiser.lr));
    const double validation = validation_l1(*vae, data, data.validation);
    const int done = epoch + 1;
    keep_if_best(done, l, validation);
    state.epoch = done;
    const double rate = static_cast<double>(order.size()) / seconds;
    run.append_metrics({{"epoch", done},
                        {"lr", lr},
                        {"train_loss", l.total},
                        {"train_reconstruction", l.recon},
                        {"train_kl", l.kl},
                        {"validation_l1", validation},
                        {"neutral_validation_l1", baselines.at("neutral")},
                        {"mean_validation_l1", baselines.at("mean")},
                        {"seconds", seconds},
                        {"samples_per_second", rate}});
    if (run.writes() && (done % config.training.checkpoint_every == 0 || done == config.training.epochs)) {
      save_vae_checkpoint(run.last_checkpoint(), *vae, &optimiser, state);
      record_checkpoint(run, state);
    }
    if (summary.epochs_run == 0) summary.first_train_loss = l.total;
    summary.last_train_loss = l.total;
    ++summary.epochs_run;
    const double eta = training_seconds / summary.epochs_run * (config.training.epochs - done);
    log::info("epoch {}/{}: loss {:.5f} ({} {:.5f}, KL {:.3f}), validation L1 {:.5f}{}, lr {:.3g}, {:.1f}s, {}{}", done,
              config.training.epochs, l.total, config.reconstruction == ReconstructionLoss::l1 ? "L1" : "squared error",
              l.recon, l.kl, validation, data.validation.empty() ? "" : versus_baseline(validation, baselines), lr,
              seconds, format_rate(rate), done < config.training.epochs ? ", eta " + format_duration(eta) : "");
  }

  // Without validation rows the best epoch is chosen by the training rows' L1 (what the
  // baselines are scored in), taken from the epoch's loss when that is the L1.
  void keep_if_best(int done, const EpochLosses& l, double validation) {
    const double criterion = !data.validation.empty()                          ? validation
                             : config.reconstruction == ReconstructionLoss::l1 ? l.recon
                                                                               : validation_l1(*vae, data, data.train);
    if (state.best_epoch < 0 || criterion < state.best_validation) {
      state.best_epoch = done;
      state.best_validation = criterion;
      if (run.writes()) save_vae_checkpoint(run.best_checkpoint(), *vae, nullptr, {done, done, criterion});
    }
  }
};

}  // namespace

VaeTrainSummary train_vae(const VaeTrainConfig& requested, const VaeTrainOptions& options) {
  Stopwatch clock;
  RunFolder run = open_run(requested.output, "vae", to_yaml(requested), options.start, options.parallel.get());
  const VaeTrainConfig config = config_of_run(run, options.start, requested, read_vae_train_config);
  const int threads = use_training_threads(config.training.threads);

  const Dataset dataset = load_training_dataset(config);
  record_fingerprint(run, "dataset", dataset.fingerprint, "dataset", config.data.dataset);
  const Normaliser& out = decoder_normaliser(dataset, config.data);
  const TrainingData data = prepare(dataset, out, config.data.validation_fraction, config.training.seed);

  torch::manual_seed(mix_seed(config.training.seed, kInitStream));
  MeshVae vae = build_vae(dataset, config);
  torch::optim::Adam optimiser(vae->parameters(), torch::optim::AdamOptions(config.optimiser.lr)
                                                      .betas({config.optimiser.beta1, config.optimiser.beta2})
                                                      .weight_decay(config.optimiser.weight_decay));
  CheckpointState state = resume_run(run, config.training.epochs, [&](const std::string& path) {
    return load_vae_checkpoint(path, *vae, &optimiser);
  });
  const bool principal_start = state.epoch == 0 && config.decoder_start == DecoderStart::principal;
  if (principal_start) start_at_principal_components(*vae, data);
  // What the run must beat, scored on the rows the best epoch is chosen by.
  const std::vector<int64_t>& scored = data.validation.empty() ? data.train : data.validation;
  const char* const loss_name = data.validation.empty() ? "training L1" : "validation L1";
  const std::map<std::string, double> baselines = trivial_l1(dataset, out, data, scored);
  run.status().baselines = baselines;
  mark_running(run);

  log::info(
      "training a VAE on {} ({}, {} vertices): {} training and {} validation samples, batch {}, {} epochs, {} "
      "threads -> {}",
      dataset.folder, to_string(dataset.kind), dataset.vertex_count(), data.train.size(), data.validation.size(),
      config.training.batch_size, config.training.epochs, threads, run.folder());
  log::info("trivial answers' {} (to beat): neutral {:.5f}, mean {:.5f}", loss_name, baselines.at("neutral"),
            baselines.at("mean"));

  VaeTrainSummary summary;
  summary.folder = run.folder();
  summary.train_samples = static_cast<int64_t>(data.train.size());
  summary.validation_samples = static_cast<int64_t>(data.validation.size());
  if (principal_start) {
    // The principal start is a model of the data already (with the encoder skip, the rank-latent
    // principal autoencoder): score it, and keep it as the best checkpoint until an epoch beats it.
    const double start = validation_l1(*vae, data, scored);
    state.best_epoch = 0;
    state.best_validation = start;
    if (run.writes()) save_vae_checkpoint(run.best_checkpoint(), *vae, nullptr, {0, 0, start});
    log::info("the start: {} {:.5f}{}", loss_name, start, versus_baseline(start, baselines));
  }
  if (options.parallel) options.parallel->warn_if_batch_too_small(config.training.batch_size, "training.batch_size");
  vae->train();
  std::unique_ptr<GradientSync> sync;
  if (options.parallel) sync = std::make_unique<GradientSync>(*options.parallel, vae->parameters());
  VaeRun epochs{config, options, run, data, vae, optimiser, baselines, state, summary, sync.get(), 0, 0};
  for (int epoch = state.epoch; epoch < config.training.epochs; ++epoch) {
    if (options.stop_after_epochs >= 0 && summary.epochs_run >= options.stop_after_epochs) break;
    epochs.epoch(epoch);
  }
  summary.epochs_done = state.epoch;
  summary.best_epoch = state.best_epoch;
  summary.best_validation = state.best_validation;
  summary.finished = state.epoch >= config.training.epochs;
  if (summary.finished) {
    const std::vector<std::string> warnings = vae_training_warnings(
        state.best_validation, state.best_epoch, state.epoch, config.training.epochs, baselines, loss_name);
    finish_run(run, state, warnings);
    for (const std::string& warning : warnings)
      if (warning.rfind("does not beat", 0) == 0) log::info("{}", trivial_answer_advice(config.reconstruction));
  }
  summary.baselines = baselines;
  summary.warnings = run.status().warnings;
  summary.seconds = clock.seconds();
  summary.samples_per_second =
      epochs.training_seconds > 0 ? static_cast<double>(epochs.samples_trained) / epochs.training_seconds : 0;
  return summary;
}

}  // namespace retarget
