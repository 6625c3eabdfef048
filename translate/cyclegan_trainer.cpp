#include "translate/cyclegan_trainer.h"

#include <ATen/CPUGeneratorImpl.h>
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/random.h"
#include "core/timer.h"
#include "models/latent_cyclegan.h"
#include "train/checkpoint.h"
#include "train/run_lifecycle.h"
#include "train/train_config.h"
#include "train/vae_run.h"
#include "translate/cyclegan_data.h"

namespace retarget {

namespace fs = std::filesystem;

namespace {

// Seed streams (core/random.h mix_seed); 11 is the light-field samples (cyclegan_data.cpp).
constexpr uint64_t kGanInitStream = 2, kGanPairSplitStream = 3, kGanPairOrderStream = 4, kGanHumanOrderStream = 5,
                   kGanAvatarOrderStream = 6;

std::string similarity_path(const RunFolder& run) { return (fs::path(run.folder()) / "similarity.yaml").string(); }

torch::Tensor rows_of(const std::vector<int64_t>& order, int64_t begin, int64_t end) {
  std::vector<int64_t> rows;
  for (int64_t i = begin; i < end; ++i) rows.push_back(order[static_cast<size_t>(i % order.size())]);
  return torch::tensor(rows, torch::kInt64);
}

// Fits S to the pairs' distances (the header's step 1) and says how well.
SimilarityFit fit_similarity(LatentCycleGanImpl& net, const LightFieldPairs& pairs, const SimilarityOptions& o,
                             uint64_t seed, std::ostream* progress_out) {
  const int64_t ph = pairs.human.size(0), pa = pairs.avatar.size(0), n = ph * pa;
  const std::vector<int64_t> order = Random(mix_seed(seed, kGanPairSplitStream)).permutation(n);
  const int64_t held = std::max<int64_t>(1, n / 10);
  const torch::Tensor held_rows = rows_of(order, 0, held), train_rows = rows_of(order, held, n);
  const torch::Tensor target = pairs.distance.reshape({-1});
  auto predict = [&](const torch::Tensor& rows) {
    return net.distance(pairs.human.index_select(0, torch::div(rows, pa, "floor")),
                        pairs.avatar.index_select(0, torch::remainder(rows, pa)));
  };
  torch::optim::Adam adam(net.similarity->parameters(), torch::optim::AdamOptions(o.lr));
  const int64_t m = train_rows.size(0), batch = o.batch_size;
  Progress progress("light-field similarity (epochs)", o.epochs, progress_out);
  for (int epoch = 0; epoch < o.epochs; ++epoch) {
    const std::vector<int64_t> shuffled =
        Random(mix_seed(seed, kGanPairOrderStream, static_cast<uint64_t>(epoch))).permutation(m);
    for (int64_t begin = 0; begin < m; begin += batch) {
      const torch::Tensor rows = train_rows.index_select(0, rows_of(shuffled, begin, std::min(m, begin + batch)));
      const torch::Tensor loss = (predict(rows) - target.index_select(0, rows)).pow(2).mean();
      adam.zero_grad();
      loss.backward();
      adam.step();
    }
    progress.advance();
  }
  progress.finish();
  torch::NoGradGuard no_grad;
  SimilarityFit fit;
  fit.pairs = n;
  fit.held_out_pairs = held;
  fit.train_mse = (predict(train_rows) - target.index_select(0, train_rows)).pow(2).mean().item<double>();
  fit.held_out_mse = (predict(held_rows) - target.index_select(0, held_rows)).pow(2).mean().item<double>();
  const double mean = target.index_select(0, train_rows).mean().item<double>();
  fit.held_out_mean_mse = (target.index_select(0, held_rows) - mean).pow(2).mean().item<double>();
  return fit;
}

void write_similarity(const RunFolder& run, const SimilarityFit& fit, const LightFieldPairs& pairs) {
  YAML::Node node;
  node["pairs"] = fit.pairs;
  node["held_out_pairs"] = fit.held_out_pairs;
  node["train_mse"] = fit.train_mse;
  node["held_out_mse"] = fit.held_out_mse;
  node["held_out_mean_mse"] = fit.held_out_mean_mse;
  node["human_meshes"] = pairs.human.size(0);
  node["avatar_meshes"] = pairs.avatar.size(0);
  node["raw_distance_min"] = pairs.raw_min;
  node["raw_distance_max"] = pairs.raw_max;
  write_file_atomically(similarity_path(run), [&](std::ostream& out) {
    out << "# the light-field similarity regressor's fit (translate/cyclegan_trainer.h): mean squared errors in "
           "normalised distance\n"
        << config_yaml_text(node);
  });
}

SimilarityFit read_similarity(const RunFolder& run) {
  const ConfigNode node = ConfigNode::load_file(similarity_path(run));
  SimilarityFit fit;
  node.get("pairs", fit.pairs);
  node.get("held_out_pairs", fit.held_out_pairs);
  node.get("train_mse", fit.train_mse);
  node.get("held_out_mse", fit.held_out_mse);
  node.get("held_out_mean_mse", fit.held_out_mean_mse);
  return fit;
}

torch::Tensor lsgan(const torch::Tensor& score, double target) { return (score - target).pow(2).mean(); }

struct GeneratorLoss {
  torch::Tensor total, adversarial, cycle_human, cycle_avatar, similarity;
};

GeneratorLoss generator_loss(LatentCycleGanImpl& net, const torch::Tensor& x, const torch::Tensor& y,
                             const CycleGanLossWeights& w) {
  GeneratorLoss l;
  const torch::Tensor gx = net.to_avatar->forward(x), fy = net.to_human->forward(y);
  l.adversarial = lsgan(net.avatar_critic->forward(gx), 1) + lsgan(net.human_critic->forward(fy), 1);
  l.cycle_human = (net.to_human->forward(gx) - x).abs().mean();
  l.cycle_avatar = (net.to_avatar->forward(fy) - y).abs().mean();
  l.similarity = 0.5 * (net.distance(x, gx).mean() + net.distance(fy, y).mean());
  l.total = w.adversarial * l.adversarial + w.cycle * (l.cycle_human + l.cycle_avatar) + w.similarity * l.similarity;
  return l;
}

torch::Tensor discriminator_loss(LatentCycleGanImpl& net, const torch::Tensor& x, const torch::Tensor& y) {
  torch::Tensor gx, fy;
  {
    torch::NoGradGuard no_grad;
    gx = net.to_avatar->forward(x);
    fy = net.to_human->forward(y);
  }
  return 0.5 * (lsgan(net.avatar_critic->forward(y), 1) + lsgan(net.avatar_critic->forward(gx), 0) +
                lsgan(net.human_critic->forward(x), 1) + lsgan(net.human_critic->forward(fy), 0));
}

CycleGanEpochMetrics evaluate(LatentCycleGanImpl& net, const CycleGanCodes& codes, const CycleGanLossWeights& w) {
  torch::NoGradGuard no_grad;
  // The larger set's codes are paired with the smaller's repeated: every code counts once.
  const int64_t n = std::max(codes.human.size(0), codes.avatar.size(0));
  auto cover = [n](const torch::Tensor& c) {
    return c.index_select(0, torch::remainder(torch::arange(n, torch::kInt64), c.size(0)));
  };
  const torch::Tensor x = cover(codes.human), y = cover(codes.avatar);
  const GeneratorLoss l = generator_loss(net, x, y, w);
  CycleGanEpochMetrics m;
  m.generator = l.total.item<double>();
  m.adversarial = l.adversarial.item<double>();
  m.cycle_human = l.cycle_human.item<double>();
  m.cycle_avatar = l.cycle_avatar.item<double>();
  m.cycle = m.cycle_human + m.cycle_avatar;
  m.similarity = l.similarity.item<double>();
  m.discriminator = discriminator_loss(net, x, y).item<double>();
  return m;
}

void log_metrics(RunFolder& run, const CycleGanEpochMetrics& m, double seconds) {
  run.append_metrics({{"epoch", m.epoch},
                      {"generator", m.generator},
                      {"adversarial", m.adversarial},
                      {"cycle", m.cycle},
                      {"cycle_human", m.cycle_human},
                      {"cycle_avatar", m.cycle_avatar},
                      {"similarity", m.similarity},
                      {"discriminator", m.discriminator},
                      {"seconds", seconds}});
}

// One epoch of alternating discriminator and generator steps (the header's step 2).
void train_epoch(LatentCycleGanImpl& net, const CycleGanCodes& codes, const CycleGanTrainConfig& config, int epoch,
                 torch::optim::Adam& generators, torch::optim::Adam& discriminators) {
  const int64_t nh = codes.human.size(0), na = codes.avatar.size(0), n = std::max(nh, na);
  const int64_t batch = config.training.batch_size;
  const auto e = static_cast<uint64_t>(epoch);
  const std::vector<int64_t> human_order =
      Random(mix_seed(config.training.seed, kGanHumanOrderStream, e)).permutation(nh);
  const std::vector<int64_t> avatar_order =
      Random(mix_seed(config.training.seed, kGanAvatarOrderStream, e)).permutation(na);
  for (int64_t begin = 0; begin < n; begin += batch) {
    const int64_t end = std::min(n, begin + batch);
    const torch::Tensor x = codes.human.index_select(0, rows_of(human_order, begin, end));
    const torch::Tensor y = codes.avatar.index_select(0, rows_of(avatar_order, begin, end));
    const torch::Tensor d = discriminator_loss(net, x, y);
    discriminators.zero_grad();
    d.backward();
    discriminators.step();
    const GeneratorLoss g = generator_loss(net, x, y, config.loss);
    generators.zero_grad();  // the critics' gradients from this loss are cleared by their next step
    g.total.backward();
    generators.step();
  }
}

std::vector<torch::Tensor> parameters_of(std::initializer_list<torch::nn::Module*> modules) {
  std::vector<torch::Tensor> out;
  for (torch::nn::Module* m : modules)
    for (const torch::Tensor& p : m->parameters()) out.push_back(p);
  return out;
}

}  // namespace

CycleGanTrainSummary train_cyclegan(const CycleGanTrainConfig& requested, const CycleGanTrainOptions& options) {
  Stopwatch clock;
  RunFolder run(requested.output, "cyclegan", to_yaml(requested), options.start);
  const CycleGanTrainConfig config = config_of_run(run, options.start, requested, read_cyclegan_train_config);
  const int threads = use_training_threads(config.training.threads);
  const uint64_t seed = config.training.seed;

  TrainedVae human = load_trained_vae(config.data.human_vae, config.data.human_checkpoint);
  TrainedVae avatar = load_trained_vae(config.data.avatar_vae, config.data.avatar_checkpoint);
  if (human.dataset.kind != DatasetKind::human) throw Error("data.human_vae", human.folder + " is not a human VAE run");
  if (avatar.dataset.kind != DatasetKind::avatar)
    throw Error("data.avatar_vae", avatar.folder + " is not an avatar VAE run");
  record_fingerprint(run, "human_dataset", human.dataset.fingerprint, "human dataset", human.dataset.folder);
  record_fingerprint(run, "avatar_dataset", avatar.dataset.fingerprint, "avatar dataset", avatar.dataset.folder);
  const CycleGanCodes codes = training_codes(human, avatar);

  torch::manual_seed(mix_seed(seed, kGanInitStream));
  LatentCycleGanOptions model;
  model.generator = config.model;
  model.generator.latent_in(codes.human.size(1)).latent_out(codes.avatar.size(1));
  model.critic_hidden = config.critic_hidden;
  LatentCycleGan net(model);
  torch::optim::Adam generators(parameters_of({net->to_avatar.ptr().get(), net->to_human.ptr().get()}),
                                torch::optim::AdamOptions(config.lr).betas({0.5, 0.999}));
  torch::optim::Adam discriminators(parameters_of({net->avatar_critic.ptr().get(), net->human_critic.ptr().get()}),
                                    torch::optim::AdamOptions(config.lr).betas({0.5, 0.999}));
  const NamedOptimizers optimisers{{"generators", &generators}, {"discriminators", &discriminators}};
  bool have_checkpoint = false;
  CheckpointState state = resume_run(run, config.training.epochs, [&](const std::string& path) {
    if (!fs::exists(path)) {
      log::warn("{}: no checkpoint yet (stopped before the similarity was fitted); starting again", run.folder());
      return CheckpointState{};
    }
    have_checkpoint = true;
    return load_checkpoint(path, *net, optimisers, "CycleGAN");
  });
  mark_running(run);

  CycleGanTrainSummary summary;
  summary.folder = run.folder();
  summary.human_codes = codes.human.size(0);
  summary.avatar_codes = codes.avatar.size(0);
  if (have_checkpoint) {
    summary.fit = read_similarity(run);
  } else {
    const LightFieldPairs pairs =
        light_field_pairs(human, avatar, codes, config.similarity.samples, config.light_field, seed, options.progress);
    summary.fit = fit_similarity(*net, pairs, config.similarity, seed, options.progress);
    write_similarity(run, summary.fit, pairs);
    save_checkpoint(run.last_checkpoint(), *net, optimisers, state);
    record_checkpoint(run, state);
  }
  log::info("light-field similarity: held-out mean squared error {:.4g} (predicting the mean: {:.4g}) on {} pairs",
            summary.fit.held_out_mse, summary.fit.held_out_mean_mse, summary.fit.held_out_pairs);
  for (torch::Tensor& p : net->similarity->parameters()) p.set_requires_grad(false);

  log::info(
      "training the latent CycleGAN ({} <-> {} codes, hidden {}) on {} human and {} avatar codes, batch {}, {} "
      "epochs, {} threads -> {}",
      codes.human.size(1), codes.avatar.size(1), config.model.hidden(), codes.human.size(0), codes.avatar.size(0),
      config.training.batch_size, config.training.epochs, threads, run.folder());
  Progress progress("training the CycleGAN (epochs)", config.training.epochs - state.epoch, options.progress);
  net->train();
  for (int epoch = state.epoch; epoch < config.training.epochs; ++epoch) {
    if (options.stop_after_epochs >= 0 && summary.epochs_run >= options.stop_after_epochs) break;
    Stopwatch epoch_clock;
    train_epoch(*net, codes, config, epoch, generators, discriminators);
    CycleGanEpochMetrics m = evaluate(*net, codes, config.loss);
    m.epoch = epoch + 1;
    if (!std::isfinite(m.generator) || !std::isfinite(m.discriminator))
      throw Error(run.folder(), fmt::format("the losses became {} (generators) and {} (discriminators) in epoch {}; "
                                            "lower optimiser.lr (now {})",
                                            m.generator, m.discriminator, m.epoch, config.lr));
    log_metrics(run, m, epoch_clock.seconds());
    state.epoch = m.epoch;
    if (state.epoch % config.training.checkpoint_every == 0 || state.epoch == config.training.epochs) {
      save_checkpoint(run.last_checkpoint(), *net, optimisers, state);
      record_checkpoint(run, state);
    }
    if (summary.epochs_run == 0) summary.first = m;
    summary.last = m;
    ++summary.epochs_run;
    progress.advance();
    if (m.epoch % std::max(1, config.training.epochs / 10) == 0 || m.epoch == config.training.epochs)
      log::info(
          "epoch {}/{}: generators {:.4g} (adversarial {:.4g}, cycle {:.4g}, similarity {:.4g}), "
          "discriminators {:.4g}",
          m.epoch, config.training.epochs, m.generator, m.adversarial, m.cycle, m.similarity, m.discriminator);
  }
  progress.finish();
  summary.epochs_done = state.epoch;
  summary.finished = state.epoch >= config.training.epochs;
  if (summary.finished) finish_run(run, state);
  summary.seconds = clock.seconds();
  return summary;
}

}  // namespace retarget
