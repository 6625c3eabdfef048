#include "pipeline/pipeline_runner.h"

#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <streambuf>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/timer.h"
#include "pipeline/input_digests.h"
#include "pipeline/run_lock.h"
#include "pipeline/stage_manifest.h"

namespace fs = std::filesystem;

namespace retarget {

namespace {

enum class Action { skip, run, resume, before_from, after_until };

struct PlannedStage {
  const Stage* stage = nullptr;
  std::string fingerprint;
  std::vector<std::string> inputs;  // "digest  path"
  std::optional<StageManifest> manifest;
  Action action = Action::run;
};

// Writes to a log file and, unless quiet, to the terminal's stream as well.
class TeeBuffer : public std::streambuf {
 public:
  TeeBuffer(std::streambuf* log, std::streambuf* terminal) : log_(log), terminal_(terminal) {}

 protected:
  int overflow(int c) override {
    if (c == traits_type::eof()) return traits_type::not_eof(c);
    log_->sputc(static_cast<char>(c));
    if (terminal_) terminal_->sputc(static_cast<char>(c));
    return c;
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    log_->sputn(s, n);
    if (terminal_) terminal_->sputn(s, n);
    return n;
  }
  int sync() override {
    log_->pubsync();
    if (terminal_) terminal_->pubsync();
    return 0;
  }

 private:
  std::streambuf* log_;
  std::streambuf* terminal_;
};

// For the duration of a stage: std::cout, std::cerr and the project's log into the stage's log
// (and the terminal unless quiet). Restores all three on destruction.
class StageOutput {
 public:
  StageOutput(const std::string& log_path, bool quiet)
      : file_(log_path, std::ios::app),
        out_(file_.rdbuf(), quiet ? nullptr : std::cout.rdbuf()),
        err_(file_.rdbuf(), quiet ? nullptr : std::cerr.rdbuf()) {
    if (!file_) throw Error(log_path, "cannot open the stage's log for writing");
    old_out_ = std::cout.rdbuf(&out_);
    old_err_ = std::cerr.rdbuf(&err_);
    old_sink_ = log::set_sink([](log::Level level, const std::string& message) {
      std::cerr << "[" << log::level_name(level) << "] " << message << "\n";
    });
  }
  ~StageOutput() {
    std::cout.flush();
    std::cerr.flush();
    log::set_sink(old_sink_);
    std::cout.rdbuf(old_out_);
    std::cerr.rdbuf(old_err_);
  }
  StageOutput(const StageOutput&) = delete;
  StageOutput& operator=(const StageOutput&) = delete;

 private:
  std::ofstream file_;
  TeeBuffer out_, err_;
  std::streambuf* old_out_ = nullptr;
  std::streambuf* old_err_ = nullptr;
  log::Sink old_sink_;
};

bool names(const Stage& stage, const std::string& name) {
  return stage.key == name || stage.family == name || stage.key.rfind(name + "/", 0) == 0;
}

// The index of the first (or last) stage `name` names; throws listing the stages otherwise.
size_t find_stage(const std::vector<Stage>& stages, const std::string& name, bool last, const std::string& option) {
  std::optional<size_t> found;
  for (size_t i = 0; i < stages.size(); ++i)
    if (names(stages[i], name) && (!found || last)) found = i;
  if (found) return *found;
  std::string keys;
  for (const Stage& s : stages) keys += (keys.empty() ? "" : ", ") + s.key;
  throw Error(option, fmt::format("no stage is called \"{}\"; the stages: {}", name, keys));
}

std::vector<PlannedStage> plan(const std::vector<Stage>& stages, const PipelineRunOptions& options) {
  const size_t from = options.from.empty() ? 0 : find_stage(stages, options.from, false, "--from");
  const size_t until = options.until.empty() ? stages.size() - 1 : find_stage(stages, options.until, true, "--until");
  if (from > until) throw Error("--from " + options.from, "comes after --until " + options.until);
  InputDigests digests;
  std::map<std::string, std::string> fingerprints;  // key -> fingerprint now
  std::vector<PlannedStage> planned;
  for (size_t i = 0; i < stages.size(); ++i) {
    PlannedStage p;
    p.stage = &stages[i];
    const Stage& s = stages[i];
    std::vector<std::string> commands, upstream;
    for (const StageCommand& c : s.commands) commands.push_back(c.text());
    for (const std::string& path : s.inputs) {
      if (path.rfind(options.run + "/", 0) == 0)
        throw Error("pipeline", "stage " + s.key + " reads " + path +
                                    " inside the run as an outside input; it must "
                                    "name the stage that writes it");
      p.inputs.push_back(digests.of(path) + "  " + path);
    }
    for (const std::string& key : s.after) {
      auto it = fingerprints.find(key);
      if (it == fingerprints.end())
        throw Error("pipeline", "stage " + s.key + " reads " + key + ", not an earlier stage");
      upstream.push_back(it->second);
    }
    p.fingerprint = stage_fingerprint(s.key, commands, p.inputs, upstream);
    p.manifest = load_stage_manifest(stage_manifest_path(options.run, s.key));
    const bool current = p.manifest && p.manifest->done() && p.manifest->fingerprint == p.fingerprint;
    if (i < from) {
      if (!p.manifest || !p.manifest->done())
        throw Error("--from " + options.from, fmt::format("stage {} before it has not finished; run without --from "
                                                          "first (or --from {})",
                                                          s.key, s.key));
      p.action = Action::before_from;
      p.fingerprint = p.manifest->fingerprint;  // what later stages were built from
    } else if (i > until) {
      p.action = Action::after_until;
    } else if (current && !options.force && options.from.empty()) {
      p.action = Action::skip;  // (never with --from: its stage and every later one rerun, they read what it rewrites)
    } else {
      const bool interrupted = p.manifest && !p.manifest->done() && p.manifest->fingerprint == p.fingerprint;
      p.action = interrupted && s.resume && !options.force && options.from.empty() ? Action::resume : Action::run;
    }
    fingerprints[s.key] = p.fingerprint;
    planned.push_back(std::move(p));
  }
  return planned;
}

// Seconds a stage is expected to take: its last recorded run, else the mean of this run's
// finished stages of its family; negative when unknown.
double estimate(const PlannedStage& p, const std::map<std::string, std::pair<double, int>>& family_times) {
  if (p.manifest && p.manifest->seconds > 0) return p.manifest->seconds;
  auto it = family_times.find(p.stage->family);
  return it == family_times.end() ? -1 : it->second.first / it->second.second;
}

std::string eta(const std::vector<PlannedStage>& planned, size_t from_index,
                const std::map<std::string, std::pair<double, int>>& family_times) {
  double known = 0;
  int unknown = 0;
  for (size_t i = from_index; i < planned.size(); ++i) {
    if (planned[i].action != Action::run && planned[i].action != Action::resume) continue;
    const double e = estimate(planned[i], family_times);
    if (e < 0)
      ++unknown;
    else
      known += e;
  }
  if (unknown == 0) return "eta " + format_duration(known);
  if (known <= 0) return fmt::format("eta unknown ({} stage{} never timed)", unknown, unknown == 1 ? "" : "s");
  return fmt::format("eta > {} ({} stage{} not timed yet)", format_duration(known), unknown, unknown == 1 ? "" : "s");
}

// The stage's commands in order; throws naming the stage, the command and its log when one fails.
void run_commands(const Stage& s, const std::vector<StageCommand>& commands, const StageCommandRunner& runner,
                  const std::string& log_path) {
  for (const StageCommand& c : commands) {
    std::cout << "$ " << c.text() << std::endl;
    int status = 0;
    try {
      status = runner(c);
    } catch (const std::exception& e) {
      throw Error("stage " + s.key, fmt::format("{} failed: {}; its output: {}", c.text(), e.what(), log_path));
    }
    if (status != 0)
      throw Error("stage " + s.key,
                  fmt::format("{} exited with status {}; its output: {}", c.text(), status, log_path));
  }
}

// The last `lines` lines of a text file.
std::string log_tail(const std::string& path, size_t lines) {
  std::ifstream in(path);
  std::vector<std::string> last;
  for (std::string line; std::getline(in, line);) {
    last.push_back(line);
    if (last.size() > lines) last.erase(last.begin());
  }
  std::string text;
  for (const std::string& line : last) text += "  " + line + "\n";
  return text;
}

void run_stage(const PlannedStage& p, const PipelineRunOptions& options, const StageCommandRunner& runner) {
  const Stage& s = *p.stage;
  std::vector<StageCommand> commands = s.commands;
  if (p.action == Action::resume) {
    if (std::optional<std::vector<StageCommand>> rest = s.resume()) commands = std::move(*rest);
  }
  if (s.expand && p.action != Action::resume) commands = s.expand();
  StageManifest m;
  m.key = s.key;
  m.fingerprint = p.fingerprint;
  m.status = "running";
  m.started = utc_timestamp();
  for (const StageCommand& c : commands) m.commands.push_back(c.text());
  m.inputs = p.inputs;
  const std::string manifest_path = stage_manifest_path(options.run, s.key);
  save_stage_manifest(manifest_path, m);
  const std::string log_path = (fs::path(options.run) / "pipeline" / (s.key + ".log")).string();
  const Stopwatch clock;
  try {
    StageOutput output(log_path, s.quiet);
    std::cout << fmt::format("== {} {}: {}\n", utc_timestamp(), s.key, s.title);
    run_commands(s, commands, runner, log_path);
    if (s.wait) s.wait();
  } catch (const Error&) {
    // A quiet stage printed only to its log: show its end, where the command said what went wrong.
    if (s.quiet) std::cerr << "the end of " << log_path << ":\n" << log_tail(log_path, 15);
    throw;
  }
  m.status = "finished";
  m.finished = utc_timestamp();
  m.seconds = clock.seconds();
  save_stage_manifest(manifest_path, m);
}

}  // namespace

void PipelineRunOptions::validate() const { require(!run.empty(), "--out", "expected the run folder"); }

PipelineRunSummary run_pipeline(const std::vector<Stage>& stages, const PipelineRunOptions& options,
                                const StageCommandRunner& runner) {
  options.validate();
  if (stages.empty()) throw Error("pipeline", "the recipe gives no stages");
  std::ostream& out = options.out ? *options.out : std::cout;
  const std::vector<PlannedStage> planned = plan(stages, options);
  PipelineRunSummary summary;
  int to_run = 0;
  for (const PlannedStage& p : planned) {
    if (p.action == Action::skip) ++summary.up_to_date;
    if (p.action == Action::run || p.action == Action::resume) ++to_run;
    if (p.action != Action::before_from && p.action != Action::after_until) ++summary.stages;
  }
  std::map<std::string, std::pair<double, int>> family_times;
  out << fmt::format("pipeline: {} stages, {} up to date, {} to run{}\n", summary.stages, summary.up_to_date, to_run,
                     to_run ? "; " + eta(planned, 0, family_times) : "")
      << std::flush;
  if (options.dry_run) {
    for (const PlannedStage& p : planned) {
      const char* what = p.action == Action::skip          ? "up to date"
                         : p.action == Action::resume      ? "resume"
                         : p.action == Action::run         ? "run"
                         : p.action == Action::before_from ? "before --from"
                                                           : "after --until";
      out << fmt::format("  {:<28} {:<14} {}\n", p.stage->key, what, p.stage->title);
    }
    return summary;
  }
  const RunLock lock(options.run);  // one pipeline per run folder
  const Stopwatch clock;
  int number = 0;
  for (size_t i = 0; i < planned.size(); ++i) {
    const PlannedStage& p = planned[i];
    if (p.action == Action::before_from || p.action == Action::after_until) continue;
    ++number;
    if (p.action == Action::skip) {
      out << fmt::format("[{}/{}] {}: up to date (took {})\n", number, summary.stages, p.stage->key,
                         format_duration(p.manifest->seconds));
      continue;
    }
    out << fmt::format("[{}/{} {} in, {}] {}{}: {}\n", number, summary.stages, format_duration(clock.seconds()),
                       eta(planned, i, family_times), p.stage->key, p.action == Action::resume ? " (resuming)" : "",
                       p.stage->title)
        << std::flush;
    const Stopwatch stage_clock;
    run_stage(p, options, runner);
    auto& [total, count] = family_times[p.stage->family];
    total += stage_clock.seconds();
    ++count;
    ++summary.ran;
    if (p.action == Action::resume) ++summary.resumed;
  }
  summary.seconds = clock.seconds();
  out << fmt::format("pipeline: {} ran ({} resumed), {} up to date, in {}\n", summary.ran, summary.resumed,
                     summary.up_to_date, format_duration(summary.seconds));
  return summary;
}

}  // namespace retarget
