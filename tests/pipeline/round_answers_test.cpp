// A round answered by people: the pipeline waits on the project's real SQLite store while
// answers arrive (given here through the store, as the web tool gives them), and returns once
// the round is decided.
#include "pipeline/round_answers.h"

#include <catch2/catch.hpp>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "annotate/annotation_store.h"
#include "cli/cli.h"
#include "correspond/annotation_project.h"
#include "tiny_correspondence.h"

using namespace retarget;
namespace fs = std::filesystem;

namespace {

int run_retarget(std::vector<std::string> args) {
  args.insert(args.begin(), "retarget");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  return cli::run(static_cast<int>(argv.size()), argv.data());
}

}  // namespace

TEST_CASE("a round answered by people: the pipeline waits until every comparison is decided", "[pipeline]") {
  const test::TinyCorrespondenceData& d = test::tiny_correspondence_data();
  const fs::path dir = test::scratch_dir("round_answers");
  const std::string corr = (dir / "c").string(), project = (dir / "p").string();
  REQUIRE(run_retarget({"correspond", "--human", d.human, "--avatar", d.avatar, "--avatar-vae", d.run, "--out", corr,
                        "--group-size", "3"}) == 0);
  REQUIRE(run_retarget({"annotate", "init", "--correspondences", corr, "--out", project}) == 0);

  std::ostringstream printed;
  std::streambuf* old = std::cout.rdbuf(printed.rdbuf());
  std::atomic<bool> returned{false};
  std::thread waiting([&] {
    wait_for_round_answers(project, 0.02);
    returned = true;
  });
  AnnotationStore store = AnnotationStore::open(load_annotation_project(project).database());
  int answered = 0;
  while (std::optional<Assignment> a = store.next_comparison("ana", 60)) {
    CHECK_FALSE(returned.load());  // still comparisons open: still waiting
    store.answer(a->comparison, "ana", Answer::left);
    ++answered;
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
  }
  waiting.join();
  std::cout.rdbuf(old);
  CHECK(returned);
  CHECK(answered > 0);
  CHECK(store.progress().finished());
  CHECK_THAT(printed.str(), Catch::Contains("retarget annotate serve " + project));
  CHECK_THAT(printed.str(), Catch::Contains(std::to_string(store.progress().total()) + " of " +
                                            std::to_string(store.progress().total()) + " comparisons decided"));
}
