#include "train/run_lifecycle.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>

#include "core/error.h"
#include "core/log.h"
#include "core/timer.h"

namespace retarget {

namespace fs = std::filesystem;

RunFolder open_run(const std::string& folder, const std::string& task, const std::string& config_yaml, RunStart start,
                   DataParallel* parallel) {
  if (!parallel) return RunFolder(folder, task, config_yaml, start);
  if (parallel->leader()) {
    RunFolder run(folder, task, config_yaml, start);
    parallel->barrier("rank 0 opening " + folder);
    return run;
  }
  parallel->barrier("rank 0 opening " + folder);
  return RunFolder::follower(folder, task, start);
}

void record_fingerprint(RunFolder& run, const std::string& key, const std::string& fingerprint, const std::string& what,
                        const std::string& where) {
  RunStatus& status = run.status();
  const auto known = status.fingerprints.find(key);
  if (known != status.fingerprints.end() && known->second != fingerprint)
    throw Error(where, fmt::format("the {} (fingerprint {}) differs from the one the run was trained on ({})", what,
                                   fingerprint, known->second));
  status.fingerprints[key] = fingerprint;
}

namespace {

// The best checkpoint on disk may be better than the one `state` (read from the last checkpoint)
// knows: written after the last checkpoint (checkpoint_every > 1) and before the run stopped.
// Its own state says what it scored; the resumed run must beat that to replace it.
void adopt_saved_best(const RunFolder& run, CheckpointState& state) {
  const std::string best = run.best_checkpoint();
  if (!fs::exists(best)) return;
  try {
    const CheckpointState saved = read_checkpoint_state(best);
    if (saved.best_epoch >= 0 && (state.best_epoch < 0 || saved.best_validation < state.best_validation)) {
      log::info("{}: the best checkpoint (epoch {}, {:.6g}) is newer than the last one; keeping it", run.folder(),
                saved.best_epoch, saved.best_validation);
      state.best_epoch = saved.best_epoch;
      state.best_validation = saved.best_validation;
    }
  } catch (const Error& e) {
    log::warn("{}; an epoch that beats the last checkpoint's best will replace it", e.what());
  }
}

}  // namespace

CheckpointState resume_run(RunFolder& run, int epochs_planned,
                           const std::function<CheckpointState(const std::string& path)>& load) {
  RunStatus& status = run.status();
  status.epochs_planned = epochs_planned;
  if (!run.resuming()) return {};
  CheckpointState state = load(run.last_checkpoint());
  adopt_saved_best(run, state);
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
