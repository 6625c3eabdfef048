#include "annotate/terminal_annotator.h"

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <sstream>
#include <string>

#include "annotate_test_support.h"

namespace retarget {

using test::scratch_dir;

namespace {

RenderPaths fake_renders() {
  RenderPaths r;
  r.anchor = [](const std::string& label) { return "/renders/human/" + label + ".png"; };
  r.candidate = [](int64_t sample) { return fmt::format("/renders/avatar/{:06d}.png", sample); };
  return r;
}

}  // namespace

TEST_CASE("a terminal session shows the three renders and records 1 / 2 answers", "[terminal]") {
  AnnotationStore store = AnnotationStore::open((scratch_dir("terminal_basic") / "a.db").string());
  store.create_group("smile", {10, 11, 12, 13}, {1, 2, 3, 4}, 5);
  std::istringstream in("1\n2\n1\n");
  std::ostringstream out;
  const TerminalSession s = run_terminal_annotator(store, "alice", fake_renders(), in, out);
  CHECK(s.decided == 3);
  CHECK_FALSE(s.quit);
  CHECK(store.finished());
  const std::string text = out.str();
  CHECK(text.find("anchor: /renders/human/smile.png") != std::string::npos);
  CHECK(text.find("1: /renders/avatar/0000") != std::string::npos);
  CHECK(text.find("2: /renders/avatar/0000") != std::string::npos);
  CHECK(text.find("is finished: sample") != std::string::npos);
  CHECK(text.find("Nothing left to compare") != std::string::npos);
}

TEST_CASE("terminal: bad input, undo and draw", "[terminal]") {
  AnnotationStore store = AnnotationStore::open((scratch_dir("terminal_keys") / "a.db").string());
  store.create_group("smile", {10, 11, 12, 13}, {1, 2, 3, 4}, 5);
  store.register_annotator("bob");  // so a draw goes to bob
  std::istringstream in("x\n  1 \nu\n2\nd\n");
  std::ostringstream out;
  const TerminalSession s = run_terminal_annotator(store, "alice", fake_renders(), in, out);
  CHECK(s.decided == 2);
  CHECK(s.undone == 1);
  CHECK(s.draws == 1);
  CHECK_FALSE(s.quit);  // after the draw nothing is left for alice: the drawn one waits for bob
  const std::string text = out.str();
  CHECK(text.find("Please type 1, 2, d, u or q.") != std::string::npos);
  CHECK(text.find("Undone: comparison") != std::string::npos);
  CHECK(text.find("Draw: the comparison goes to another annotator.") != std::string::npos);
  // One first-round comparison answered (right, after the undo), the other drawn and waiting.
  const std::vector<DecisionRecord> d = store.decisions();
  REQUIRE(d.size() == 2);
  CHECK(d[0].answer == Answer::right);
  CHECK(d[1].answer == Answer::draw);
  CHECK(text.find("Nothing left to compare for now") != std::string::npos);
  const std::optional<Assignment> next = store.next_comparison("bob", 60);
  REQUIRE(next);
  CHECK(next->comparison == d[1].comparison);
}

TEST_CASE("terminal: quitting or the end of input hands the shown comparison back", "[terminal]") {
  AnnotationStore store = AnnotationStore::open((scratch_dir("terminal_quit") / "a.db").string());
  store.create_group("smile", {10, 11}, {1, 2}, 5);
  for (const std::string input : {"q\n", ""}) {
    std::istringstream in(input);
    std::ostringstream out;
    CHECK(run_terminal_annotator(store, "alice", fake_renders(), in, out).quit);
    CHECK(store.comparisons()[0].state == ComparisonState::open);
  }
}

TEST_CASE("terminal: an error is printed and the session goes on", "[terminal]") {
  AnnotationStore store = AnnotationStore::open((scratch_dir("terminal_error") / "a.db").string());
  store.create_group("smile", {10, 11}, {1, 2}, 5);
  std::istringstream in("u\n1\n");
  std::ostringstream out;
  const TerminalSession s = run_terminal_annotator(store, "alice", fake_renders(), in, out);
  CHECK(out.str().find("Error: ") != std::string::npos);
  CHECK(out.str().find("has no answer to undo") != std::string::npos);
  CHECK(s.decided == 1);
  CHECK(store.finished());
}

}  // namespace retarget
