// The folder of one training run, shared by every trainer:
//
//   config.yaml            the run's config with every key written out (what it was trained with)
//   run.yaml               status (running | finished), task, epochs done of planned, the best
//                          epoch and its validation loss, the dataset fingerprints, the software
//                          version, start / update / finish times (UTC), the trivial answers'
//                          validation losses (`baselines`) and what went wrong (`warnings`)
//   metrics.jsonl          one JSON object per finished epoch
//   metrics.csv            the same rows as CSV, with a header
//   checkpoints/last.pt    everything needed to resume (weights, optimiser state, epoch, best)
//   checkpoints/best.pt    the weights of the epoch with the lowest validation loss (VAE runs)
//   checkpoints/<name>.pt  other snapshots a trainer keeps (translation runs: stage<N>.pt)
//
// Every file except the two metrics logs is written atomically. The logs are appended a line
// at a time; on resume they are cut back to the epochs the last checkpoint contains, so a run
// that was killed and resumed has the same logs as one that was not.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/log.h"

namespace retarget {

// How to treat an existing run folder.
enum class RunStart {
  fresh,   // the folder must be new, empty, or hold no run.yaml
  resume,  // continue the unfinished run in the folder from checkpoints/last.pt
  force,   // delete the run's files and start again
};

struct RunStatus {
  std::string status = "running";  // "running" or "finished"
  std::string task;                // "vae", ...
  int epochs_done = 0;             // epochs in checkpoints/last.pt
  int epochs_planned = 0;
  int best_epoch = -1;  // 1-based epoch of checkpoints/best.pt; -1: none yet
  double best_validation = 0;
  std::map<std::string, std::string> fingerprints;  // e.g. "dataset" -> topology fingerprint
  std::string software_version, started, updated, finished;
  // The trivial answers' loss in the units of best_validation (VAE runs: the normalised
  // validation L1 of "neutral" and "mean"), what the run must beat. Empty in older run.yaml files.
  std::map<std::string, double> baselines;
  // Why the run may be no good ("does not beat the trivial answer: ..."), one sentence each.
  std::vector<std::string> warnings;

  // Reads run.yaml of `folder`; throws retarget::Error naming the file if it is unreadable.
  // `baselines` and `warnings` are optional (files written before them load with neither).
  static RunStatus load(const std::string& folder);
  void save(const std::string& folder) const;  // atomically; sets nothing itself
};

class RunFolder {
 public:
  // Opens `folder` for a run of `task` with the given config text:
  //   fresh:  throws if the folder holds a run ("finished ... use --force to train again" or
  //           "unfinished, epoch 12 of 100 ... use --resume to continue or --force")
  //   resume: throws if there is no run to resume, or it is finished, or its task differs; the
  //           run's own config.yaml is kept (the caller reads it back with config_path())
  //   force:  removes config.yaml, run.yaml, the metrics logs and checkpoints/
  RunFolder(const std::string& folder, const std::string& task, const std::string& config_yaml, RunStart start);

  const std::string& folder() const { return folder_; }
  std::string config_path() const;      // folder/config.yaml
  std::string last_checkpoint() const;  // folder/checkpoints/last.pt
  std::string best_checkpoint() const;  // folder/checkpoints/best.pt
  // folder/checkpoints/<name>.pt (e.g. the translation trainer's stage snapshots "stage2")
  std::string checkpoint_path(const std::string& name) const;
  bool resuming() const { return resuming_; }

  RunStatus& status() { return status_; }
  void save_status();  // stamps `updated` and writes run.yaml

  // Appends one epoch's metrics to metrics.jsonl and metrics.csv. `columns` fixes the CSV
  // header on the first call; every row must have the same keys. Values are written with
  // full precision; "epoch" should be among them.
  void append_metrics(const std::vector<std::pair<std::string, double>>& row);
  // Keeps only the logged rows with epoch <= `epochs` (on resume: the checkpoint's epoch).
  void truncate_metrics(int epochs);

  // A rank other than 0 of a data-parallel run (train/data_parallel.h): the folder rank 0 opened
  // with `start` (it must have already), read and never written: save_status, append_metrics and
  // truncate_metrics do nothing, and the trainer writes no checkpoint (writes() is false). It
  // resumes when rank 0 does: `start` is resume and checkpoints/last.pt exists.
  static RunFolder follower(const std::string& folder, const std::string& task, RunStart start);
  bool writes() const { return !follower_; }

 private:
  RunFolder() = default;
  std::string folder_;
  bool resuming_ = false;
  bool follower_ = false;
  RunStatus status_;
};

// Reads metrics.jsonl of a run folder: one map per epoch (tests and reports).
std::vector<std::map<std::string, double>> read_metrics(const std::string& folder);

// The config a run goes on with: `requested`, or with RunStart::resume the config.yaml the run
// was started with, read by `read` (ConfigNode -> Config), with a warning when the two differ.
// to_yaml(Config) gives the text that is compared.
template <typename Config, typename Read>
Config config_of_run(const RunFolder& run, RunStart start, const Config& requested, Read read) {
  if (start != RunStart::resume) return requested;
  Config config = read(ConfigNode::load_file(run.config_path()));
  if (to_yaml(config) != to_yaml(requested))
    log::warn("resuming {} with the config it was started with ({}), not {}", run.folder(), run.config_path(),
              requested.source);
  return config;
}

}  // namespace retarget
