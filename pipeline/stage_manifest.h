// The record a stage of `retarget pipeline` leaves in RUN/pipeline/<key>.yaml: the fingerprint
// it ran with, whether it finished, when, how long it took, its commands and its inputs'
// digests. Written atomically twice: at the start (status: running) and at the end (finished),
// so that a rerun after a kill knows the stage was interrupted with the same inputs (and can
// resume it) and a finished stage with the same fingerprint is skipped.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace retarget {

struct StageManifest {
  std::string key;
  std::string fingerprint;  // 64 hex digits (SHA-256)
  std::string status;       // "running" or "finished"
  std::string started;      // UTC, ISO 8601
  std::string finished;     // UTC, empty while running
  double seconds = 0;       // wall time of the last run that finished
  std::vector<std::string> commands;
  std::vector<std::string> inputs;  // "digest  path"
  bool done() const { return status == "finished"; }
};

// RUN/pipeline/<key>.yaml
std::string stage_manifest_path(const std::string& run, const std::string& key);

// The manifest at `path`, or nullopt when there is none. Throws retarget::Error naming the file
// for one that does not parse (a manifest is only ever replaced whole, so this means someone
// edited it).
std::optional<StageManifest> load_stage_manifest(const std::string& path);

// Writes the manifest atomically (core/atomic_file.h), creating the folder.
void save_stage_manifest(const std::string& path, const StageManifest& manifest);

}  // namespace retarget
