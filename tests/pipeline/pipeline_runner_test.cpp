// The runner of `retarget pipeline` on stages whose commands are a real function writing real
// files: what it skips, what it runs again when an input changes, how it resumes a stage a kill
// interrupted, --from and --until, and what a failing command reports.
#include "pipeline/pipeline_runner.h"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "pipeline/run_lock.h"
#include "pipeline/stage_manifest.h"
#include "scratch.h"

using namespace retarget;
using namespace retarget::test;
namespace fs = std::filesystem;

namespace {

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// "retarget copy FROM TO" copies a file; "retarget append FILE TEXT" appends a line; "retarget
// fail" exits with 3. Each command run is recorded in `log`.
struct Commands {
  std::vector<std::string> log;
  int operator()(const StageCommand& c) {
    log.push_back(c.text());
    if (c.args.at(0) == "copy") fs::copy_file(c.args.at(1), c.args.at(2), fs::copy_options::overwrite_existing);
    if (c.args.at(0) == "append") std::ofstream(c.args.at(1), std::ios::app) << c.args.at(2) << "\n";
    if (c.args.at(0) == "fail") return 3;
    return 0;
  }
};

// input.txt -> a (copy) -> b (append to a copy of a) ; c appends to its own file.
std::vector<Stage> three_stages(const fs::path& dir) {
  const std::string run = (dir / "run").string();
  Stage a;
  a.key = "data/a";
  a.family = "copy";
  a.title = "copy the input";
  a.commands = {{"retarget", {"copy", (dir / "input.txt").string(), run + "/a.txt"}}};
  a.inputs = {(dir / "input.txt").string()};
  Stage b;
  b.key = "b";
  b.family = "append";
  b.title = "append to a copy of a";
  b.commands = {{"retarget", {"copy", run + "/a.txt", run + "/b.txt"}}, {"retarget", {"append", run + "/b.txt", "b"}}};
  b.after = {"data/a"};
  Stage c;
  c.key = "c";
  c.family = "append";
  c.title = "append on its own";
  c.commands = {{"retarget", {"append", run + "/c.txt", "c"}}};
  return {a, b, c};
}

PipelineRunOptions options_for(const fs::path& dir, std::ostream& out) {
  PipelineRunOptions o;
  o.run = (dir / "run").string();
  o.out = &out;
  return o;
}

}  // namespace

TEST_CASE("a second run skips every stage that is up to date; a changed input reruns its stage and those after it",
          "[pipeline]") {
  const fs::path dir = scratch_dir("pipeline_runner_skip");
  fs::create_directories(dir / "run");
  write_file(dir, "input.txt", "one\n");
  const std::vector<Stage> stages = three_stages(dir);
  std::ostringstream out;
  Commands first;
  PipelineRunSummary s = run_pipeline(stages, options_for(dir, out), std::ref(first));
  CHECK(s.ran == 3);
  CHECK(first.log.size() == 4);
  CHECK(read_text(dir / "run/b.txt") == "one\nb\n");
  const std::optional<StageManifest> m = load_stage_manifest(stage_manifest_path((dir / "run").string(), "data/a"));
  REQUIRE(m);
  CHECK(m->done());
  CHECK(m->fingerprint.size() == 64);
  CHECK(m->inputs.size() == 1);
  CHECK(fs::exists(dir / "run/pipeline/data/a.log"));

  Commands second;
  s = run_pipeline(stages, options_for(dir, out), std::ref(second));
  CHECK(s.ran == 0);
  CHECK(s.up_to_date == 3);
  CHECK(second.log.empty());

  write_file(dir, "input.txt", "two\n");  // a's input: a and b (which reads a) run, c does not
  Commands third;
  s = run_pipeline(stages, options_for(dir, out), std::ref(third));
  CHECK(s.ran == 2);
  CHECK(s.up_to_date == 1);
  CHECK(read_text(dir / "run/b.txt") == "two\nb\n");
  CHECK(read_text(dir / "run/c.txt") == "c\n");

  std::vector<Stage> changed = three_stages(dir);  // a changed command: only c
  changed[2].commands[0].args[2] = "c2";
  Commands fourth;
  s = run_pipeline(changed, options_for(dir, out), std::ref(fourth));
  CHECK(s.ran == 1);
  CHECK(read_text(dir / "run/c.txt") == "c\nc2\n");
}

TEST_CASE("a stage a kill interrupted resumes with its resume commands when its inputs are the same", "[pipeline]") {
  const fs::path dir = scratch_dir("pipeline_runner_resume");
  fs::create_directories(dir / "run");
  write_file(dir, "input.txt", "x\n");
  std::vector<Stage> stages = three_stages(dir);
  const std::string run = (dir / "run").string();
  stages[1].resume = [run]() -> std::optional<std::vector<StageCommand>> {
    return std::vector<StageCommand>{{"retarget", {"append", run + "/b.txt", "resumed"}}};
  };
  std::ostringstream out;
  Commands first;
  run_pipeline(stages, options_for(dir, out), std::ref(first));
  // What a kill during b leaves: its manifest says running, with the fingerprint it started with.
  const std::string path = stage_manifest_path(run, "b");
  StageManifest m = *load_stage_manifest(path);
  m.status = "running";
  save_stage_manifest(path, m);
  Commands second;
  const PipelineRunSummary s = run_pipeline(stages, options_for(dir, out), std::ref(second));
  CHECK(s.ran == 1);
  CHECK(s.resumed == 1);
  REQUIRE(second.log.size() == 1);
  CHECK(second.log[0] == "retarget append " + run + "/b.txt resumed");
  CHECK(load_stage_manifest(path)->done());
  CHECK_THAT(out.str(), Catch::Contains("b (resuming)"));

  // Interrupted but with other inputs since: start over, not resume.
  m.status = "running";
  m.fingerprint = std::string(64, '0');
  save_stage_manifest(path, m);
  Commands third;
  run_pipeline(stages, options_for(dir, out), std::ref(third));
  CHECK(third.log.size() == 2);  // b's own two commands
}

TEST_CASE("from and until: --from reruns its stage and every later one, --until stops after its stage", "[pipeline]") {
  const fs::path dir = scratch_dir("pipeline_runner_from");
  fs::create_directories(dir / "run");
  write_file(dir, "input.txt", "x\n");
  const std::vector<Stage> stages = three_stages(dir);
  std::ostringstream out;
  PipelineRunOptions until = options_for(dir, out);
  until.until = "data";  // a key's folder names the stages under it
  Commands first;
  PipelineRunSummary s = run_pipeline(stages, until, std::ref(first));
  CHECK(s.ran == 1);
  CHECK_FALSE(fs::exists(dir / "run/b.txt"));

  PipelineRunOptions from = options_for(dir, out);
  from.from = "c";
  CHECK_THAT(error_of([&] { run_pipeline(stages, from, Commands()); }),
             Catch::Contains("stage b before it has not finished"));

  Commands second;
  s = run_pipeline(stages, options_for(dir, out), std::ref(second));
  CHECK(s.ran == 2);
  from.from = "append";  // a family: its first stage is b
  Commands third;
  s = run_pipeline(stages, from, std::ref(third));
  CHECK(s.ran == 2);
  CHECK(read_text(dir / "run/b.txt") == "x\nb\n");

  PipelineRunOptions unknown = options_for(dir, out);
  unknown.until = "nothing";
  CHECK_THAT(error_of([&] { run_pipeline(stages, unknown, Commands()); }),
             Catch::Contains("--until: no stage is called \"nothing\"; the stages: data/a, b, c"));
}

TEST_CASE("a failing command stops the pipeline naming its stage and log; a rerun continues there", "[pipeline]") {
  const fs::path dir = scratch_dir("pipeline_runner_fail");
  fs::create_directories(dir / "run");
  write_file(dir, "input.txt", "x\n");
  std::vector<Stage> stages = three_stages(dir);
  const StageCommand good = stages[1].commands[1];
  stages[1].commands[1] = {"retarget", {"fail"}};
  std::ostringstream out;
  const std::string message = error_of([&] { run_pipeline(stages, options_for(dir, out), Commands()); });
  CHECK_THAT(message, Catch::Contains("stage b: retarget fail exited with status 3; its output: "));
  CHECK_THAT(message, Catch::Contains("run/pipeline/b.log"));
  CHECK_FALSE(load_stage_manifest(stage_manifest_path((dir / "run").string(), "b"))->done());
  stages[1].commands[1] = good;
  Commands second;
  const PipelineRunSummary s = run_pipeline(stages, options_for(dir, out), std::ref(second));
  CHECK(s.up_to_date == 1);  // a
  CHECK(s.ran == 2);
}

TEST_CASE("one pipeline at a time per run folder: a second is refused, naming the first's pid", "[pipeline]") {
  const fs::path dir = scratch_dir("pipeline_runner_lock");
  fs::create_directories(dir / "run");
  write_file(dir, "input.txt", "x\n");
  const std::vector<Stage> stages = three_stages(dir);
  std::ostringstream out;
  {
    const RunLock first((dir / "run").string());
    const std::string message = error_of([&] { run_pipeline(stages, options_for(dir, out), Commands()); });
    CHECK_THAT(message, Catch::Contains("another `retarget pipeline` (pid " + std::to_string(::getpid()) + ")"));
    CHECK_FALSE(fs::exists(dir / "run/a.txt"));  // nothing ran
  }
  Commands after;  // released: the next run goes ahead
  CHECK(run_pipeline(stages, options_for(dir, out), std::ref(after)).ran == 3);
}
