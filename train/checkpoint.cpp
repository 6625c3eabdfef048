#include "train/checkpoint.h"

#include <fmt/format.h>

#include <filesystem>

#include "core/atomic_file.h"
#include "core/error.h"

namespace retarget {

namespace fs = std::filesystem;

void save_checkpoint(const std::string& path, const torch::nn::Module& module, torch::optim::Optimizer* optimizer,
                     const CheckpointState& state) {
  torch::serialize::OutputArchive archive;
  torch::serialize::OutputArchive weights;
  for (const auto& p : module.named_parameters()) weights.write(p.key(), p.value().detach());
  archive.write("weights", weights);
  if (optimizer) {
    torch::serialize::OutputArchive optimiser_archive;
    optimizer->save(optimiser_archive);
    archive.write("optimiser", optimiser_archive);
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
  if (!fs::exists(path)) throw Error(path, "no such checkpoint");
  torch::serialize::InputArchive archive;
  try {
    archive.load_from(path);
  } catch (const c10::Error& e) {
    throw Error(path, std::string("not a readable checkpoint: ") + e.what_without_backtrace());
  }
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
  if (optimizer) {
    torch::serialize::InputArchive optimiser_archive;
    if (!archive.try_read("optimiser", optimiser_archive)) throw Error(path, "holds no optimiser state to resume from");
    optimizer->load(optimiser_archive);
  }
  CheckpointState state;
  torch::Tensor t;
  if (archive.try_read("epoch", t)) state.epoch = static_cast<int>(t.item<int64_t>());
  if (archive.try_read("best_epoch", t)) state.best_epoch = static_cast<int>(t.item<int64_t>());
  if (archive.try_read("best_validation", t)) state.best_validation = t.item<double>();
  return state;
}

}  // namespace retarget
