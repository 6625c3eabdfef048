#include "train/run_lifecycle.h"

#include <fmt/format.h>

#include <algorithm>

#include "core/error.h"
#include "core/log.h"
#include "core/timer.h"

namespace retarget {

void record_fingerprint(RunFolder& run, const std::string& key, const std::string& fingerprint, const std::string& what,
                        const std::string& where) {
  RunStatus& status = run.status();
  const auto known = status.fingerprints.find(key);
  if (known != status.fingerprints.end() && known->second != fingerprint)
    throw Error(where, fmt::format("the {} (fingerprint {}) differs from the one the run was trained on ({})", what,
                                   fingerprint, known->second));
  status.fingerprints[key] = fingerprint;
}

CheckpointState resume_run(RunFolder& run, int epochs_planned,
                           const std::function<CheckpointState(const std::string& path)>& load) {
  RunStatus& status = run.status();
  status.epochs_planned = epochs_planned;
  if (!run.resuming()) return {};
  const CheckpointState state = load(run.last_checkpoint());
  if (state.epoch != status.epochs_done)
    log::warn("{}: run.yaml says epoch {}, the checkpoint holds epoch {}; going on from the checkpoint", run.folder(),
              status.epochs_done, state.epoch);
  status.epochs_done = state.epoch;
  status.best_epoch = state.best_epoch;
  status.best_validation = state.best_validation;
  run.truncate_metrics(state.epoch);
  log::info("resuming {} after epoch {} of {}", run.folder(), state.epoch, epochs_planned);
  return state;
}

void mark_running(RunFolder& run) {
  run.status().status = "running";
  run.save_status();
}

void record_checkpoint(RunFolder& run, const CheckpointState& state) {
  RunStatus& status = run.status();
  status.epochs_done = state.epoch;
  status.best_epoch = state.best_epoch;
  status.best_validation = state.best_validation;
  run.save_status();
}

void finish_run(RunFolder& run, const CheckpointState& state, const std::vector<std::string>& warnings) {
  RunStatus& status = run.status();
  for (const std::string& warning : warnings) {
    log::warn("{}: {}", run.folder(), warning);
    if (std::find(status.warnings.begin(), status.warnings.end(), warning) == status.warnings.end())
      status.warnings.push_back(warning);
  }
  status.status = "finished";
  status.epochs_done = state.epoch;
  status.finished = utc_timestamp();
  run.save_status();
}

}  // namespace retarget
