#include "train/checkpoint.h"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/error.h"

namespace retarget {

namespace fs = std::filesystem;

namespace {

// One scalar of the state: read into a fresh tensor each time (a tensor given to try_read is
// overwritten in place, keeping its dtype: an int64 tensor reused for a float64 value reads the
// float's bits as an integer). Absent: `fallback`; present but not one finite number: an error.
double read_scalar(torch::serialize::InputArchive& archive, const std::string& key, double fallback,
                   const std::string& path) {
  torch::Tensor value;
  if (!archive.try_read(key, value)) return fallback;
  if (value.numel() != 1)
    throw Error(path, fmt::format("state '{}' holds {} values, expected one", key, value.numel()));
  const double number = value.to(torch::kFloat64).item<double>();
  if (!std::isfinite(number)) throw Error(path, fmt::format("state '{}' is {}, expected a finite number", key, number));
  return number;
}

int read_count(torch::serialize::InputArchive& archive, const std::string& key, int fallback, const std::string& path) {
  const double number = read_scalar(archive, key, fallback, path);
  if (number != std::floor(number) || number < -1 || number > 1e9)
    throw Error(path, fmt::format("state '{}' is {}, expected a whole number of epochs", key, number));
  return static_cast<int>(number);
}

CheckpointState read_state(torch::serialize::InputArchive& archive, const std::string& path) {
  CheckpointState state;
  state.epoch = read_count(archive, "epoch", state.epoch, path);
  state.best_epoch = read_count(archive, "best_epoch", state.best_epoch, path);
  state.best_validation = read_scalar(archive, "best_validation", state.best_validation, path);
  return state;
}

torch::serialize::InputArchive open_archive(const std::string& path) {
  if (!fs::exists(path)) throw Error(path, "no such checkpoint");
  torch::serialize::InputArchive archive;
  try {
    archive.load_from(path);
  } catch (const c10::Error& e) {
    throw Error(path, std::string("not a readable checkpoint: ") + e.what_without_backtrace());
  }
  return archive;
}

}  // namespace

void save_checkpoint(const std::string& path, const torch::nn::Module& module, torch::optim::Optimizer* optimizer,
                     const CheckpointState& state) {
  NamedOptimizers optimizers;
  if (optimizer) optimizers.emplace_back("optimiser", optimizer);
  save_checkpoint(path, module, optimizers, state);
}

void save_checkpoint(const std::string& path, const torch::nn::Module& module, const NamedOptimizers& optimizers,
                     const CheckpointState& state) {
  torch::serialize::OutputArchive archive;
  torch::serialize::OutputArchive weights;
  for (const auto& p : module.named_parameters()) weights.write(p.key(), p.value().detach());
  archive.write("weights", weights);
  for (const auto& [name, optimizer] : optimizers) {
    torch::serialize::OutputArchive optimiser_archive;
    optimizer->save(optimiser_archive);
    archive.write(name, optimiser_archive);
  }
  archive.write("epoch", torch::tensor(static_cast<int64_t>(state.epoch)));
  archive.write("best_epoch", torch::tensor(static_cast<int64_t>(state.best_epoch)));
  archive.write("best_validation", torch::tensor(state.best_validation, torch::kFloat64));
  const std::string temporary = temporary_path_for(path);
  try {
    archive.save_to(temporary);
    commit_temporary_file(temporary, path);
  } catch (const c10::Error& e) {
    discard_temporary_file(temporary);
    throw Error(path, std::string("cannot write the checkpoint: ") + e.what_without_backtrace());
  } catch (...) {
    discard_temporary_file(temporary);
    throw;
  }
}

CheckpointState load_checkpoint(const std::string& path, torch::nn::Module& module, torch::optim::Optimizer* optimizer,
                                const std::string& what) {
  NamedOptimizers optimizers;
  if (optimizer) optimizers.emplace_back("optimiser", optimizer);
  return load_checkpoint(path, module, optimizers, what);
}

CheckpointState load_checkpoint(const std::string& path, torch::nn::Module& module, const NamedOptimizers& optimizers,
                                const std::string& what) {
  torch::serialize::InputArchive archive = open_archive(path);
  torch::serialize::InputArchive weights;
  if (!archive.try_read("weights", weights)) throw Error(path, "not a " + what + " checkpoint (no weights)");
  {
    torch::NoGradGuard no_grad;
    for (auto& p : module.named_parameters()) {
      torch::Tensor value;
      if (!weights.try_read(p.key(), value))
        throw Error(path, fmt::format("has no parameter '{}': trained with another architecture?", p.key()));
      if (value.sizes() != p.value().sizes())
        throw Error(path, fmt::format("parameter '{}' is {} in the checkpoint but {} in the model (model sizes "
                                      "differ from the config it was trained with?)",
                                      p.key(), c10::str(value.sizes()), c10::str(p.value().sizes())));
      p.value().copy_(value);
    }
  }
  for (const auto& [name, optimizer] : optimizers) {
    torch::serialize::InputArchive optimiser_archive;
    if (!archive.try_read(name, optimiser_archive))
      throw Error(path, name == "optimiser" ? std::string("holds no optimiser state to resume from")
                                            : fmt::format("holds no state of the {} optimiser to resume from", name));
    optimizer->load(optimiser_archive);
  }
  return read_state(archive, path);
}

CheckpointState read_checkpoint_state(const std::string& path) {
  torch::serialize::InputArchive archive = open_archive(path);
  return read_state(archive, path);
}

}  // namespace retarget
