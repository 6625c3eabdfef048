// One stage of `retarget pipeline`: a few commands (`retarget` subcommands or `retarget-infer`)
// that write one place in the run folder, with what its result depends on.
//
// A stage is up to date when its manifest (RUN/pipeline/<key>.yaml, pipeline/stage_manifest.h)
// records the fingerprint it has now: the digest of its commands, of the files it reads from
// outside the run (recipes, rigs, configs: by content) and of the fingerprints of the stages it
// reads from. Changing any of them makes it, and everything reading from it, run again.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace retarget {

struct StageCommand {
  std::string program;            // "retarget" or "retarget-infer"
  std::vector<std::string> args;  // after the program's name: {"train", CONFIG, "--out", RUN, ...}
  std::string text() const;       // "retarget train CONFIG --out RUN" (arguments with spaces quoted)
};

struct Stage {
  std::string key;     // where its manifest is, e.g. "datasets/human", "method/round-03"
  std::string family;  // stages alike for --from/--until and estimates: "round", "train", ...
  std::string title;   // one line for people: "round 3 of 22: one informative pair per expression"
  std::vector<StageCommand> commands;
  std::vector<std::string> inputs;  // files and folders outside the run it reads (digested by content)
  std::vector<std::string> after;   // keys of the stages whose results it reads
  bool quiet = false;               // its commands' output only in its log (many small stages)
  // When the stage started before with the same fingerprint and did not finish (killed), the
  // commands that continue it instead of `commands` (a training's --resume): nullopt to start
  // over, an empty list when nothing was left to do.
  std::function<std::optional<std::vector<StageCommand>>()> resume;
  // The commands to run, when they can only be listed once earlier stages ran (pictures of a
  // rig's files); `commands` then states them for the fingerprint. Empty: `commands`.
  std::function<std::vector<StageCommand>()> expand;
  // After the commands: wait until the stage's work is done elsewhere (people answering a round
  // in the web tool). Returns when done; throws to stop the pipeline.
  std::function<void()> wait;
};

}  // namespace retarget
