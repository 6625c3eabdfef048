// The steps every trainer (train/vae_trainer.h, translate/translation_trainer.h) takes around its
// epochs, on its run folder (train/run_folder.h) and its checkpoints (train/checkpoint.h), so
// that run.yaml means the same in every run:
//
//   record_fingerprint   a dataset's topology fingerprint into run.yaml; a resumed run refuses
//                        a dataset other than the one it was trained on
//   resume_run           checkpoints/last.pt back into the model and optimiser, run.yaml and the
//                        metric logs cut back to the epoch it holds
//   mark_running         run.yaml says "running"
//   record_checkpoint    after each write of checkpoints/last.pt: run.yaml says how far it is
//   finish_run           run.yaml says "finished", with the run's warnings
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "train/checkpoint.h"
#include "train/data_parallel.h"
#include "train/run_folder.h"

namespace retarget {

// Opens the run folder as RunFolder(folder, task, config_yaml, start) does; in a data-parallel
// run, rank 0 opens it and the other ranks follow it (RunFolder::follower) once it has.
RunFolder open_run(const std::string& folder, const std::string& task, const std::string& config_yaml, RunStart start,
                   DataParallel* parallel);

// Records `fingerprint` as the run's fingerprint `key` ("dataset", "human_dataset", ...). Throws
// retarget::Error at `where` (the dataset's folder or the config key naming it) when the run
// already recorded another one: "the <what> (fingerprint A) differs from the one the run was
// trained on (B)".
void record_fingerprint(RunFolder& run, const std::string& key, const std::string& fingerprint, const std::string& what,
                        const std::string& where);

// Reads checkpoints/last.pt of a resuming run through `load` (which fills the model and the
// optimiser and returns where the run stood), warns when run.yaml says another epoch (the
// checkpoint wins), copies the epoch and the best epoch into run.yaml's status and cuts the
// metric logs back to the checkpoint's epoch. When checkpoints/best.pt scored better than the
// best the last checkpoint knows (written after it), its score is the one to beat: a resumed run
// never replaces a better best.pt. A fresh run: returns the zero state, loads nothing.
CheckpointState resume_run(RunFolder& run, int epochs_planned,
                           const std::function<CheckpointState(const std::string& path)>& load);

// Sets status "running" and writes run.yaml.
void mark_running(RunFolder& run);

// After checkpoints/last.pt was written with `state`: run.yaml's epochs done and best epoch
// follow it, written at once.
void record_checkpoint(RunFolder& run, const CheckpointState& state);

// Marks the run finished at `state`'s epoch (UTC time stamp) and adds each of `warnings` not
// already in run.yaml's list, logging it as a warning.
void finish_run(RunFolder& run, const CheckpointState& state, const std::vector<std::string>& warnings = {});

}  // namespace retarget
