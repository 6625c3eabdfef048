// Runs the stages of `retarget pipeline` in order, skipping those that are up to date and
// resuming the one a kill interrupted (pipeline/stage.h, pipeline/stage_manifest.h).
//
//   RUN/pipeline/<key>.yaml   each stage's manifest (fingerprint, status, times, commands, inputs)
//   RUN/pipeline/<key>.log    each stage's output, appended run after run
//
// Before anything runs, every stage's fingerprint is computed (they depend on commands, outside
// inputs and upstream fingerprints only, never on outputs), so the plan is known up front: which
// stages are up to date, which run, which resume. Progress: one line per stage with its number,
// the time so far and an ETA from the durations earlier runs recorded (or, for stages never
// timed, from finished stages of the same family in this run).
#pragma once

#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

#include "pipeline/stage.h"

namespace retarget {

struct PipelineRunOptions {
  std::string run;              // the run folder
  std::string from;             // run this stage (key, key prefix or family) and every later one, up to date or not
  std::string until;            // stop after the last stage this names
  bool force = false;           // run every selected stage, up to date or not
  bool dry_run = false;         // print the plan, run nothing
  std::ostream* out = nullptr;  // progress (nullptr: std::cout)
  void validate() const;
};

// Runs one command; returns its exit status (0: success). The pipeline command maps "retarget"
// and "retarget-infer" onto the programs' own functions, in this process.
using StageCommandRunner = std::function<int(const StageCommand&)>;

struct PipelineRunSummary {
  int stages = 0;  // selected
  int ran = 0;
  int resumed = 0;  // of ran: continued from a kill
  int up_to_date = 0;
  double seconds = 0;
};

// Throws retarget::Error naming the stage (and its log) when a command fails or throws; stages
// before it keep their results, so a rerun continues there. --from/--until that name no stage,
// or --from with an earlier stage that never finished, throw before anything runs.
PipelineRunSummary run_pipeline(const std::vector<Stage>& stages, const PipelineRunOptions& options,
                                const StageCommandRunner& runner);

}  // namespace retarget
