#include "annotate/annotation_store.h"

#include <fmt/format.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "annotate/sqlite.h"
#include "annotate/tournament.h"
#include "annotate_test_support.h"
#include "core/error.h"

namespace retarget {
namespace {

using test::make_test_group;
using test::ManualClock;
using test::scratch_dir;
using test::TestGroup;

const TestGroup* find_group(const std::vector<TestGroup>& groups, const std::string& label) {
  for (const TestGroup& g : groups) {
    if (g.label == label) return &g;
  }
  return nullptr;
}

// One annotator answers with the consistent oracle until nothing is left to it.
int answer_with_oracle(AnnotationStore& store, const std::string& annotator, const std::vector<TestGroup>& groups) {
  int answered = 0;
  while (std::optional<Assignment> a = store.next_comparison(annotator, 60)) {
    store.answer(a->comparison, annotator, test::oracle(*find_group(groups, a->label), *a));
    ++answered;
  }
  return answered;
}

int64_t add(AnnotationStore& store, const TestGroup& g, uint64_t seed = 1) {
  return store.create_group(g.label, g.samples, g.distances, seed);
}

// Every decided comparison has exactly one verdict, and the comparisons in the store are exactly
// the decided and ready matches of the tournament its results describe: no half-applied round.
void check_consistent(AnnotationStore& store) {
  std::map<int64_t, int> verdicts;
  for (const DecisionRecord& d : store.decisions()) {
    if (d.answer != Answer::draw) ++verdicts[d.comparison];
  }
  for (const GroupInfo& g : store.groups()) {
    const std::vector<ComparisonRecord> rows = store.comparisons(g.id);
    Tournament t(static_cast<int>(g.candidates.size()), g.seed);
    auto slot = [&](int64_t sample) {
      return static_cast<int>(std::find(g.candidates.begin(), g.candidates.end(), sample) - g.candidates.begin());
    };
    std::vector<ComparisonRecord> sorted = rows;
    std::sort(sorted.begin(), sorted.end(), [](const ComparisonRecord& a, const ComparisonRecord& b) {
      return std::make_pair(a.round, a.position) < std::make_pair(b.round, b.position);
    });
    for (const ComparisonRecord& c : sorted) {
      if (c.state == ComparisonState::decided) {
        CHECK(verdicts[c.id] == 1);
        t.decide(c.round, c.position, slot(*c.winner));
      } else {
        CHECK(verdicts[c.id] == 0);
      }
    }
    std::set<std::pair<int, int>> expected, stored;
    for (const Match& m : t.decided()) expected.insert({m.round, m.position});
    for (const Match& m : t.ready()) expected.insert({m.round, m.position});
    for (const ComparisonRecord& c : rows) stored.insert({c.round, c.position});
    CHECK(stored == expected);
  }
}

}  // namespace

TEST_CASE("store options are checked", "[store]") {
  StoreOptions options;
  options.active_seconds = 0;
  CHECK_THROWS_WITH(options.validate(), Catch::Contains("store.active_seconds: expected a positive number"));
  options = {};
  options.busy_timeout_seconds = -1;
  CHECK_THROWS_WITH(AnnotationStore::open((scratch_dir("options") / "a.db").string(), options),
                    Catch::Contains("store.busy_timeout_seconds"));
}

TEST_CASE("a new store has the schema, and reopening keeps the data", "[store]") {
  const std::string path = (scratch_dir("reopen") / "sub" / "annotations.db").string();
  const TestGroup g = make_test_group("smile", 16);
  {
    AnnotationStore store = AnnotationStore::open(path);
    CHECK(add(store, g) == 1);
    CHECK(store.comparisons().size() == 8);
  }
  AnnotationStore store = AnnotationStore::open(path);
  const std::vector<GroupInfo> groups = store.groups();
  REQUIRE(groups.size() == 1);
  CHECK(groups[0].label == "smile");
  CHECK(groups[0].candidates == g.samples);
  CHECK(groups[0].distances == g.distances);
  CHECK(groups[0].seed == 1);
  CHECK(store.comparisons().size() == 8);
  CHECK_FALSE(store.finished());
}

TEST_CASE("opening something that is not a store of this version fails clearly", "[store]") {
  const auto dir = scratch_dir("bad_files");
  const std::string text = (dir / "notes.txt").string();
  std::ofstream(text) << "this is not a database, it is a text file with enough bytes to have a header ......";
  CHECK_THROWS_WITH(AnnotationStore::open(text), Catch::Contains("notes.txt") && Catch::Contains("not a database"));

  const std::string foreign = (dir / "foreign.db").string();
  {
    sqlite::Database db = sqlite::Database::open(foreign);
    db.exec("CREATE TABLE people (name TEXT)", "create a table");
  }
  CHECK_THROWS_WITH(AnnotationStore::open(foreign),
                    Catch::Contains("foreign.db") && Catch::Contains("not an annotation store"));

  const std::string future = (dir / "future.db").string();
  AnnotationStore::open(future);
  {
    sqlite::Database db = sqlite::Database::open(future);
    db.exec("UPDATE meta SET value = '99' WHERE key = 'schema_version'", "fake a newer version");
  }
  CHECK_THROWS_WITH(AnnotationStore::open(future), Catch::Contains("future.db") &&
                                                       Catch::Contains("schema version 99") &&
                                                       Catch::Contains("this build reads version 2"));
}

TEST_CASE("a version 1 store is upgraded on open and keeps its answers; sessions persist", "[store]") {
  const std::string path = (scratch_dir("upgrade") / "annotations.db").string();
  int64_t comparison = 0;
  {
    AnnotationStore store = AnnotationStore::open(path);
    const TestGroup g = make_test_group("smile", 4);
    add(store, g);
    const std::optional<Assignment> a = store.next_comparison("ana", 60);
    REQUIRE(a);
    comparison = a->comparison;
    store.answer(a->comparison, "ana", Answer::left);
  }
  {
    // What version 1 wrote: no sessions table.
    sqlite::Database db = sqlite::Database::open(path);
    db.exec("DROP TABLE sessions; UPDATE meta SET value = '1' WHERE key = 'schema_version'", "make a version 1 file");
  }
  {
    AnnotationStore store = AnnotationStore::open(path);
    CHECK(store.progress().done() == 1);
    CHECK(store.has_comparison(comparison));
    CHECK_FALSE(store.has_comparison(comparison + 1000));
    CHECK(store.has_sample(101));
    CHECK_FALSE(store.has_sample(99));
    CHECK_FALSE(store.has_session("ana"));
    store.add_session("0123456789abcdef0123", "ana");
    CHECK_THROWS_WITH(store.add_session("short", "ana"), Catch::Contains("at least 16"));
  }
  AnnotationStore store = AnnotationStore::open(path);
  CHECK(store.session_annotator("0123456789abcdef0123") == std::optional<std::string>("ana"));
  CHECK_FALSE(store.session_annotator("fedcba9876543210fedc"));
  CHECK(store.has_session("ana"));
  const std::optional<Assignment> held = store.next_comparison("ana", 60);
  REQUIRE(held);
  CHECK(store.progress().held == 1);
  const SessionsEnded ended = store.end_sessions("ana");
  CHECK(ended.sessions == 1);
  CHECK(ended.released == 1);
  CHECK_FALSE(store.has_session("ana"));
  CHECK(store.progress().held == 0);
  CHECK_THROWS_WITH(store.end_sessions("nobody"), Catch::Contains("unknown annotator 'nobody'"));
}

TEST_CASE("16 candidates take 15 comparisons and the oracle's best is the champion", "[store]") {
  const int count = GENERATE(16, 5, 11, 2);
  const auto dir = scratch_dir(fmt::format("oracle_{}", count));
  AnnotationStore store = AnnotationStore::open((dir / "a.db").string());
  const std::vector<TestGroup> groups = {make_test_group("smile", count, 100), make_test_group("frown", count, 500)};
  for (const TestGroup& g : groups) add(store, g, 7);
  CHECK(answer_with_oracle(store, "alice", groups) == 2 * (count - 1));
  CHECK(store.finished());
  const StoreProgress p = store.progress();
  REQUIRE(p.groups.size() == 2);
  for (size_t i = 0; i < 2; ++i) {
    CHECK(p.groups[i].done == count - 1);
    CHECK(p.groups[i].total == count - 1);
    REQUIRE(p.groups[i].champion);
    CHECK(*p.groups[i].champion == groups[i].best());
  }
  REQUIRE(p.annotators.size() == 1);
  CHECK(p.annotators[0].name == "alice");
  CHECK(p.annotators[0].decided == 2 * (count - 1));
  CHECK(store.comparisons().size() == static_cast<size_t>(2 * (count - 1)));
  check_consistent(store);
}

TEST_CASE("answer reports the winner, the comparisons it opened and the champion", "[store]") {
  AnnotationStore store = AnnotationStore::open((scratch_dir("answer_result") / "a.db").string());
  const TestGroup g = make_test_group("smile", 4);
  add(store, g);
  const Assignment a = *store.next_comparison("alice", 60);
  AnswerResult r = store.answer(a.comparison, "alice", Answer::left);
  CHECK(r.status == AnswerStatus::decided);
  CHECK(r.winner == a.left);
  CHECK(r.opened.empty());
  const Assignment b = *store.next_comparison("alice", 60);
  r = store.answer(b.comparison, "alice", Answer::right);
  REQUIRE(r.opened.size() == 1);
  const Assignment final = *store.next_comparison("alice", 60);
  CHECK(final.comparison == r.opened[0]);
  CHECK(final.round == 2);
  CHECK(final.left == a.left);
  CHECK(final.right == b.right);
  r = store.answer(final.comparison, "alice", Answer::right);
  CHECK(r.champion == b.right);
  CHECK_FALSE(store.next_comparison("alice", 60));
}

TEST_CASE("bad ids, wrong annotators and second answers give clear errors", "[store]") {
  AnnotationStore store = AnnotationStore::open((scratch_dir("errors") / "errors.db").string());
  const TestGroup g = make_test_group("smile", 4);
  add(store, g);
  const Assignment a = *store.next_comparison("alice", 60);
  store.register_annotator("bob");

  CHECK_THROWS_WITH(store.answer(999, "alice", Answer::left),
                    Catch::Contains("errors.db") && Catch::Contains("comparison 999 does not exist"));
  CHECK_THROWS_WITH(store.answer(a.comparison, "carol", Answer::left), Catch::Contains("unknown annotator 'carol'"));
  CHECK_THROWS_WITH(store.answer(a.comparison, "bob", Answer::left),
                    Catch::Contains(fmt::format("annotator 'bob' does not hold comparison {}", a.comparison)) &&
                        Catch::Contains("leased to 'alice'"));
  const int64_t other = a.comparison == 1 ? 2 : 1;  // open, leased to nobody
  CHECK_THROWS_WITH(store.answer(other, "alice", Answer::left),
                    Catch::Contains("does not hold comparison") && Catch::Contains("back in the queue"));

  store.answer(a.comparison, "alice", Answer::left);
  CHECK_THROWS_WITH(
      store.answer(a.comparison, "alice", Answer::right),
      Catch::Contains(fmt::format("comparison {} is already decided ('alice' chose left)", a.comparison)));
  CHECK_THROWS_WITH(store.answer(a.comparison, "bob", Answer::right), Catch::Contains("already decided"));
  CHECK(store.decisions().size() == 1);

  CHECK_THROWS_WITH(store.release(other, "bob"), Catch::Contains("annotator 'bob' cannot release comparison"));
  CHECK_THROWS_WITH(store.next_comparison("alice", 0), Catch::Contains("lease_seconds must be a positive number"));
  CHECK_THROWS_WITH(store.next_comparison("", 10), Catch::Contains("annotator name is empty"));
  CHECK_THROWS_WITH(store.group(42), Catch::Contains("group 42 does not exist"));
  CHECK_THROWS_WITH(store.undo_last("bob"), Catch::Contains("annotator 'bob' has no answer to undo"));

  CHECK_THROWS_WITH(store.create_group("smile", {1, 2}, {0.1, 0.2}, 1),
                    Catch::Contains("create_group('smile'): a group with this label already exists (group 1)"));
  CHECK_THROWS_WITH(store.create_group("", {1, 2}, {0.1, 0.2}, 1), Catch::Contains("label"));
  CHECK_THROWS_WITH(store.create_group("one", {1}, {0.1}, 1), Catch::Contains("needs at least 2 candidates, got 1"));
  CHECK_THROWS_WITH(store.create_group("mismatch", {1, 2, 3}, {0.1, 0.2}, 1),
                    Catch::Contains("3 candidates but 2 distances"));
  CHECK_THROWS_WITH(store.create_group("twice", {1, 2, 1}, {0.1, 0.2, 0.3}, 1),
                    Catch::Contains("sample 1 is listed twice (candidate 2)"));
  CHECK_THROWS_WITH(store.create_group("nan", {1, 2}, {0.1, std::nan("")}, 1),
                    Catch::Contains("the distance of candidate 1 (sample 2) is nan"));
  CHECK(store.groups().size() == 1);  // nothing half-created
}

TEST_CASE("a draw goes to another annotator, never back to the one who drew", "[store]") {
  AnnotationStore store = AnnotationStore::open((scratch_dir("draw_other") / "a.db").string());
  const TestGroup g = make_test_group("smile", 2);
  add(store, g);
  store.register_annotator("bob");
  const Assignment a = *store.next_comparison("alice", 60);
  const AnswerResult r = store.answer(a.comparison, "alice", Answer::draw);
  CHECK(r.status == AnswerStatus::requeued);
  CHECK_FALSE(r.winner);
  CHECK_FALSE(store.next_comparison("alice", 60));  // bob has not drawn it: it waits for him

  const std::vector<ComparisonRecord> rows = store.comparisons();
  REQUIRE(rows.size() == 1);
  CHECK(rows[0].state == ComparisonState::open);
  CHECK(rows[0].draw_count == 1);
  CHECK(rows[0].drawn_by == std::vector<std::string>{"alice"});

  const Assignment b = *store.next_comparison("bob", 60);
  CHECK(b.comparison == a.comparison);
  const AnswerResult decided = store.answer(b.comparison, "bob", Answer::right);
  CHECK(decided.status == AnswerStatus::decided);
  CHECK(decided.champion == b.right);
  const std::vector<Triplet> t = store.triplets();
  REQUIRE(t.size() == 1);
  CHECK_FALSE(t[0].tie_break);
  CHECK(t[0].positive == b.right);
}

TEST_CASE("with one annotator a second draw is settled by the tie-break and marked", "[store]") {
  ManualClock clock;
  StoreOptions options;
  options.clock = clock.function();
  options.active_seconds = 600;
  AnnotationStore store = AnnotationStore::open((scratch_dir("tie_break") / "a.db").string(), options);
  // Sample 11 is closer to y0 than sample 10, whatever the tournament's left and right are.
  store.create_group("smile", {10, 11}, {2.5, 0.5}, 3);
  store.register_annotator("ghost");  // inactive long before the session: does not hold anything up
  clock.advance(3600);

  const Assignment first = *store.next_comparison("alice", 60);
  CHECK(store.answer(first.comparison, "alice", Answer::draw).status == AnswerStatus::requeued);
  const Assignment again = *store.next_comparison("alice", 60);  // back in the queue once
  CHECK(again.comparison == first.comparison);
  const AnswerResult r = store.answer(again.comparison, "alice", Answer::draw);
  CHECK(r.status == AnswerStatus::tie_break);
  CHECK(r.winner == 11);
  CHECK(r.champion == 11);

  const std::vector<Triplet> t = store.triplets();
  REQUIRE(t.size() == 1);
  CHECK(t[0].positive == 11);
  CHECK(t[0].negative == 10);
  CHECK(t[0].tie_break);
  const std::vector<DecisionRecord> d = store.decisions();
  REQUIRE(d.size() == 3);  // two draws by alice, the tie-break by nobody
  CHECK(d[2].tie_break);
  CHECK(d[2].annotator.empty());
  CHECK(store.progress().groups[0].tie_breaks == 1);
  CHECK(store.comparisons()[0].draw_count == 2);
}

TEST_CASE("when every active annotator has drawn, the comparison goes round once more", "[store]") {
  AnnotationStore store = AnnotationStore::open((scratch_dir("all_drew") / "a.db").string());
  store.create_group("smile", {10, 11}, {0.5, 2.5}, 3);
  store.register_annotator("alice");
  store.register_annotator("bob");
  Assignment a = *store.next_comparison("alice", 60);
  CHECK(store.answer(a.comparison, "alice", Answer::draw).status == AnswerStatus::requeued);
  a = *store.next_comparison("bob", 60);
  CHECK(store.answer(a.comparison, "bob", Answer::draw).status == AnswerStatus::requeued);
  // Both drew: alice may have it again; a second draw by someone who drew settles it.
  a = *store.next_comparison("alice", 60);
  const AnswerResult r = store.answer(a.comparison, "alice", Answer::draw);
  CHECK(r.status == AnswerStatus::tie_break);
  CHECK(r.winner == 10);
}

TEST_CASE("an expired lease is handed out again", "[store]") {
  ManualClock clock;
  StoreOptions options;
  options.clock = clock.function();
  AnnotationStore store = AnnotationStore::open((scratch_dir("lease") / "a.db").string(), options);
  store.create_group("smile", {10, 11}, {0.5, 2.5}, 3);
  const Assignment a = *store.next_comparison("alice", 30);
  CHECK(a.lease_expires == Approx(*clock.seconds + 30));
  CHECK_FALSE(store.next_comparison("bob", 30));  // alice's lease is live
  // Asking again renews alice's lease on the same comparison.
  clock.advance(20);
  CHECK(store.next_comparison("alice", 30)->comparison == a.comparison);
  clock.advance(20);
  CHECK_FALSE(store.next_comparison("bob", 30));
  clock.advance(31);  // alice walked away
  const Assignment b = *store.next_comparison("bob", 30);
  CHECK(b.comparison == a.comparison);
  CHECK_THROWS_WITH(store.answer(a.comparison, "alice", Answer::left), Catch::Contains("leased to 'bob'"));
  store.answer(b.comparison, "bob", Answer::left);
  CHECK(store.decisions().size() == 1);
  CHECK(store.finished());
}

TEST_CASE("an expired lease that nobody took can still be answered by its holder", "[store]") {
  ManualClock clock;
  StoreOptions options;
  options.clock = clock.function();
  AnnotationStore store = AnnotationStore::open((scratch_dir("lease_late") / "a.db").string(), options);
  store.create_group("smile", {10, 11}, {0.5, 2.5}, 3);
  const Assignment a = *store.next_comparison("alice", 30);
  clock.advance(100);
  CHECK(store.answer(a.comparison, "alice", Answer::right).status == AnswerStatus::decided);
}

TEST_CASE("release hands a comparison back to the queue", "[store]") {
  AnnotationStore store = AnnotationStore::open((scratch_dir("release") / "a.db").string());
  store.create_group("smile", {10, 11}, {0.5, 2.5}, 3);
  const Assignment a = *store.next_comparison("alice", 600);
  store.release(a.comparison, "alice");
  CHECK(store.next_comparison("bob", 600)->comparison == a.comparison);
}

TEST_CASE("undo takes back the last answer and hands the comparison back", "[store]") {
  AnnotationStore store = AnnotationStore::open((scratch_dir("undo") / "a.db").string());
  const TestGroup g = make_test_group("smile", 4);
  add(store, g);
  const Assignment a = *store.next_comparison("alice", 60);
  store.answer(a.comparison, "alice", Answer::left);
  const Assignment back = store.undo_last("alice");
  CHECK(back.comparison == a.comparison);
  CHECK(store.decisions().empty());
  CHECK(store.comparisons()[0].state == ComparisonState::assigned);
  CHECK(store.next_comparison("alice", 60)->comparison == a.comparison);  // still hers
  store.answer(a.comparison, "alice", Answer::right);
  CHECK(store.triplets()[0].positive == a.right);
  check_consistent(store);
}

TEST_CASE("undo withdraws the next-round comparison it fed, unless that was answered", "[store]") {
  AnnotationStore store = AnnotationStore::open((scratch_dir("undo_dependent") / "a.db").string());
  const TestGroup g = make_test_group("smile", 4);
  add(store, g);
  const Assignment a = *store.next_comparison("alice", 60);
  store.answer(a.comparison, "alice", Answer::left);
  const Assignment b = *store.next_comparison("bob", 60);
  const AnswerResult rb = store.answer(b.comparison, "bob", Answer::left);
  REQUIRE(rb.opened.size() == 1);
  const int64_t final_id = rb.opened[0];

  // bob's answer fed the final, which nobody has answered: the final is withdrawn.
  store.undo_last("bob");
  CHECK(store.comparisons().size() == 2);
  store.answer(b.comparison, "bob", Answer::left);
  const int64_t new_final = store.comparisons().back().id;
  CHECK(new_final != final_id);  // ids are never reused
  CHECK_THROWS_WITH(store.answer(final_id, "bob", Answer::left), Catch::Contains("withdrawn"));

  // Once the final is decided, the answers that fed it cannot be undone.
  const Assignment f = *store.next_comparison("carol", 60);
  store.answer(f.comparison, "carol", Answer::right);
  CHECK_THROWS_WITH(
      store.undo_last("alice"),
      Catch::Contains(fmt::format("cannot undo annotator 'alice''s answer to comparison {}", a.comparison)) &&
          Catch::Contains("has already been answered"));
  // carol's final can be undone, then alice's.
  store.undo_last("carol");
  store.release(f.comparison, "carol");
  store.undo_last("alice");
  CHECK(store.comparisons().size() == 2);
  CHECK(store.decisions().size() == 1);
  check_consistent(store);
}

TEST_CASE("undo of a draw, and of the draw that triggered a tie-break", "[store]") {
  AnnotationStore store = AnnotationStore::open((scratch_dir("undo_draw") / "a.db").string());
  store.create_group("smile", {10, 11}, {0.5, 2.5}, 3);
  Assignment a = *store.next_comparison("alice", 60);
  store.answer(a.comparison, "alice", Answer::draw);
  a = *store.next_comparison("alice", 60);
  CHECK(store.answer(a.comparison, "alice", Answer::draw).status == AnswerStatus::tie_break);
  CHECK(store.finished());

  store.undo_last("alice");  // the second draw and its tie-break
  CHECK_FALSE(store.finished());
  std::vector<ComparisonRecord> rows = store.comparisons();
  CHECK(rows[0].state == ComparisonState::assigned);
  CHECK(rows[0].assigned_to == "alice");
  CHECK(rows[0].draw_count == 1);
  CHECK(store.decisions().size() == 1);

  store.undo_last("alice");  // the first draw
  rows = store.comparisons();
  CHECK(rows[0].draw_count == 0);
  CHECK(rows[0].drawn_by.empty());
  CHECK(store.decisions().empty());
  store.answer(a.comparison, "alice", Answer::right);
  CHECK(store.triplets()[0].positive == a.right);
  CHECK_FALSE(store.triplets()[0].tie_break);

  // A draw someone else has since decided cannot be undone.
  store.create_group("frown", {20, 21}, {0.5, 2.5}, 3);
  store.register_annotator("bob");
  a = *store.next_comparison("alice", 60);
  store.answer(a.comparison, "alice", Answer::draw);
  a = *store.next_comparison("bob", 60);
  store.answer(a.comparison, "bob", Answer::left);
  CHECK_THROWS_WITH(store.undo_last("alice"), Catch::Contains("'bob' has decided it since"));
}

TEST_CASE("triplets: direct and derived, and the CSV export holds exactly the same", "[store]") {
  const auto dir = scratch_dir("triplets");
  AnnotationStore store = AnnotationStore::open((dir / "a.db").string());
  const std::vector<TestGroup> groups = {make_test_group("smile, wide", 16, 100),
                                         make_test_group("say \"oh\"", 5, 500)};
  for (const TestGroup& g : groups) add(store, g, 4);
  answer_with_oracle(store, "alice", groups);

  const std::vector<Triplet> direct = store.triplets(false);
  const std::vector<Triplet> all = store.triplets(true);
  CHECK(direct.size() == 15 + 4);
  // 16 candidates: 17 derived (see tournament_test.cpp); 5 candidates: the champion's chain.
  size_t derived = 0;
  for (const Triplet& t : all) {
    derived += t.derived;
    const TestGroup& g = *find_group(groups, t.anchor);
    CHECK(g.score_of(t.positive) < g.score_of(t.negative));  // the oracle is consistent, so is the closure
  }
  CHECK(all.size() == direct.size() + derived);
  CHECK(std::count_if(all.begin(), all.end(), [](const Triplet& t) { return t.derived && t.group == 1; }) == 17);

  const std::string csv = (dir / "out" / "triplets.csv").string();
  store.export_csv(csv);
  std::ifstream in(csv);
  std::stringstream text;
  text << in.rdbuf();
  std::string expected = "group,anchor,positive,negative,derived,tie_break\n";
  for (const Triplet& t : all) {
    expected += fmt::format("{},{},{},{},{},{}\n", t.group, csv_field(t.anchor), t.positive, t.negative,
                            t.derived ? 1 : 0, t.tie_break ? 1 : 0);
  }
  CHECK(text.str() == expected);
  CHECK(text.str().find("\"smile, wide\"") != std::string::npos);
  CHECK(text.str().find("\"say \"\"oh\"\"\"") != std::string::npos);

  store.export_csv(csv, false);
  std::ifstream again(csv);
  std::string line;
  int lines = 0;
  while (std::getline(again, line)) ++lines;
  CHECK(lines == 1 + 19);
}

TEST_CASE("the store survives a killed writer: every committed decision, no half-applied round", "[store][fork]") {
  const auto dir = scratch_dir("killed");
  const std::string path = (dir / "a.db").string();
  // Enough work (20 groups, 295 comparisons) that the child is still busy when it is killed.
  std::vector<TestGroup> groups;
  for (int g = 0; g < 20; ++g)
    groups.push_back(make_test_group(fmt::format("expression {}", g), g % 2 ? 11 : 16, 100 * g));
  {
    AnnotationStore store = AnnotationStore::open(path);
    for (const TestGroup& g : groups) add(store, g, 9);
  }  // no connection crosses the fork

  const bool clean_exit = GENERATE(false, true);
  int pipe_fds[2];
  REQUIRE(::pipe(pipe_fds) == 0);
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    ::close(pipe_fds[0]);
    int status = 0;
    try {
      AnnotationStore store = AnnotationStore::open(path);
      for (int n = 0;; ++n) {
        std::optional<Assignment> a = store.next_comparison("child", 600);
        if (!a) break;
        store.answer(a->comparison, "child", test::oracle(*find_group(groups, a->label), *a));
        // Reported only once answer() has returned, that is, committed.
        if (::write(pipe_fds[1], &a->comparison, sizeof a->comparison) != sizeof a->comparison) break;
        if (clean_exit && n == 11) ::_exit(0);  // no destructor, no close: as abrupt as a crash
      }
    } catch (...) {
      status = 3;
    }
    ::_exit(status);
  }
  ::close(pipe_fds[1]);
  std::vector<int64_t> acknowledged;
  int64_t id = 0;
  while (::read(pipe_fds[0], &id, sizeof id) == sizeof id) {
    acknowledged.push_back(id);
    if (!clean_exit && acknowledged.size() == 17) ::kill(child, SIGKILL);  // mid-way, maybe mid-transaction
  }
  ::close(pipe_fds[0]);
  int status = 0;
  ::waitpid(child, &status, 0);
  if (clean_exit) {
    CHECK(WIFEXITED(status));
    CHECK(acknowledged.size() == 12);
  } else {
    CHECK(WIFSIGNALED(status));
    CHECK(acknowledged.size() >= 17);
  }

  // Reopen as the child's lease has run out (an hour later).
  StoreOptions options;
  options.clock = [] {
    return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count() + 3600;
  };
  AnnotationStore store = AnnotationStore::open(path, options);
  {
    sqlite::Database db = sqlite::Database::open(path);
    sqlite::Statement check(db, "PRAGMA integrity_check", "check integrity");
    sqlite::Query q(check);
    REQUIRE(q.next());
    CHECK(q.text(0) == "ok");
  }
  std::set<int64_t> decided;
  for (const ComparisonRecord& c : store.comparisons()) {
    if (c.state == ComparisonState::decided) decided.insert(c.id);
  }
  for (int64_t c : acknowledged) CHECK(decided.count(c));
  CHECK(decided.size() >= acknowledged.size());
  CHECK(decided.size() <= acknowledged.size() + 1);  // at most the answer in flight when killed
  check_consistent(store);

  // And the work goes on where the child stopped.
  answer_with_oracle(store, "parent", groups);
  CHECK(store.finished());
  for (const GroupProgress& g : store.progress().groups) CHECK(*g.champion == find_group(groups, g.label)->best());
  CHECK(store.decisions().size() == 10 * 15 + 10 * 10);
}

TEST_CASE("several processes may create and open a new store at the same moment", "[store][fork]") {
  const std::string path = (scratch_dir("open_race") / "a.db").string();
  std::vector<pid_t> children;
  for (int p = 0; p < 12; ++p) {
    const pid_t child = ::fork();
    REQUIRE(child >= 0);
    if (child == 0) {
      try {
        AnnotationStore store = AnnotationStore::open(path);
        store.register_annotator(fmt::format("process {}", p));
      } catch (...) {
        ::_exit(3);
      }
      ::_exit(0);
    }
    children.push_back(child);
  }
  for (pid_t child : children) {
    int status = 0;
    ::waitpid(child, &status, 0);
    CHECK(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 0);
  }
  CHECK(AnnotationStore::open(path).progress().annotators.size() == 12);
}

TEST_CASE("two annotators on two connections complete a group: no lost or duplicated decision", "[store][threads]") {
  const std::string path = (scratch_dir("two_threads") / "a.db").string();
  const std::vector<TestGroup> groups = {make_test_group("smile", 16)};
  {
    AnnotationStore store = AnnotationStore::open(path);
    add(store, groups[0], 2);
  }
  std::atomic<int> answered[2] = {0, 0};
  std::atomic<bool> failed{false};
  auto work = [&](int who) {
    try {
      const std::string name = who == 0 ? "alice" : "bob";
      AnnotationStore store = AnnotationStore::open(path);
      while (true) {
        std::optional<Assignment> a = store.next_comparison(name, 60);
        if (!a) {
          if (store.finished()) return;
          std::this_thread::yield();
          continue;
        }
        store.answer(a->comparison, name, test::oracle(groups[0], *a));
        ++answered[who];
      }
    } catch (const std::exception& e) {
      failed = true;
      std::fprintf(stderr, "annotator thread failed: %s\n", e.what());
    }
  };
  std::thread t0(work, 0), t1(work, 1);
  t0.join();
  t1.join();
  REQUIRE_FALSE(failed);
  CHECK(answered[0] + answered[1] == 15);

  AnnotationStore store = AnnotationStore::open(path);
  const std::vector<DecisionRecord> d = store.decisions();
  CHECK(d.size() == 15);
  std::set<int64_t> compared;
  for (const DecisionRecord& r : d) compared.insert(r.comparison);
  CHECK(compared.size() == 15);
  CHECK(store.comparisons().size() == 15);
  CHECK(*store.progress().groups[0].champion == groups[0].best());
  check_consistent(store);
}

TEST_CASE("50 concurrent annotators answer 2,000 comparisons", "[store][threads][performance]") {
  const std::string path = (scratch_dir("fifty_threads") / "a.db").string();
  std::vector<TestGroup> groups;
  for (int g = 0; g < 100; ++g) groups.push_back(make_test_group(fmt::format("expression {}", g), 21, 1000 * g));
  {
    AnnotationStore store = AnnotationStore::open(path);
    for (const TestGroup& g : groups) add(store, g, static_cast<uint64_t>(g.samples[0]));
  }
  std::map<std::string, const TestGroup*> by_label;
  for (const TestGroup& g : groups) by_label[g.label] = &g;

  constexpr int kThreads = 50;
  std::atomic<int> answered{0};
  std::atomic<bool> failed{false};
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::thread> threads;
  for (int i = 0; i < kThreads; ++i) {
    threads.emplace_back([&, i] {
      try {
        const std::string name = fmt::format("annotator-{}", i);
        AnnotationStore store = AnnotationStore::open(path);
        while (true) {
          std::optional<Assignment> a = store.next_comparison(name, 60);
          if (!a) {
            if (store.finished()) return;
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
            continue;
          }
          store.answer(a->comparison, name, test::oracle(*by_label.at(a->label), *a));
          ++answered;
        }
      } catch (const std::exception& e) {
        failed = true;
        std::fprintf(stderr, "annotator thread failed: %s\n", e.what());
      }
    });
  }
  for (std::thread& t : threads) t.join();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  REQUIRE_FALSE(failed);
  CHECK(answered == 2000);
  std::fprintf(stderr, "[annotate] %d threads answered %d comparisons in %.2f s (%.0f answers/s)\n", kThreads,
               answered.load(), seconds, answered / seconds);

  AnnotationStore store = AnnotationStore::open(path);
  CHECK(store.finished());
  const std::vector<DecisionRecord> d = store.decisions();
  CHECK(d.size() == 2000);
  std::set<int64_t> compared;
  for (const DecisionRecord& r : d) compared.insert(r.comparison);
  CHECK(compared.size() == 2000);
  for (const GroupProgress& g : store.progress().groups) CHECK(*g.champion == by_label.at(g.label)->best());
}

}  // namespace retarget
