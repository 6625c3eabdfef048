#include "annotate/annotation_store.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <set>
#include <unordered_map>
#include <utility>

#include "annotate/sqlite.h"
#include "annotate/tournament.h"
#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"

namespace retarget {

using sqlite::Database;
using sqlite::Query;
using sqlite::Statement;
using sqlite::Transaction;

namespace {

constexpr const char* kApplication = "retarget-annotate";

// The schema of version 1; version 2 adds kSchemaV2Sessions (below). Comparison and decision ids are AUTOINCREMENT
// so an id that an undo withdrew is never reused for another comparison (an annotator may still hold the old one).
constexpr const char* kSchemaV1 = R"sql(
CREATE TABLE meta (
  key TEXT PRIMARY KEY,
  value TEXT NOT NULL
) WITHOUT ROWID;

CREATE TABLE annotators (
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL UNIQUE,
  created_at REAL NOT NULL,
  last_seen REAL NOT NULL
);

CREATE TABLE groups (
  id INTEGER PRIMARY KEY AUTOINCREMENT,
  label TEXT NOT NULL UNIQUE,
  seed INTEGER NOT NULL,
  candidate_count INTEGER NOT NULL CHECK (candidate_count >= 2),
  created_at REAL NOT NULL
);

CREATE TABLE candidates (
  group_id INTEGER NOT NULL REFERENCES groups(id),
  slot INTEGER NOT NULL,
  sample INTEGER NOT NULL,
  distance REAL NOT NULL,
  PRIMARY KEY (group_id, slot),
  UNIQUE (group_id, sample)
) WITHOUT ROWID;

CREATE TABLE comparisons (
  id INTEGER PRIMARY KEY AUTOINCREMENT,
  group_id INTEGER NOT NULL REFERENCES groups(id),
  round INTEGER NOT NULL CHECK (round >= 1),
  position INTEGER NOT NULL CHECK (position >= 0),
  left_slot INTEGER NOT NULL,
  right_slot INTEGER NOT NULL,
  state TEXT NOT NULL DEFAULT 'open' CHECK (state IN ('open', 'assigned', 'decided')),
  assigned_to INTEGER REFERENCES annotators(id),
  assigned_at REAL,
  lease_expires REAL,
  draw_count INTEGER NOT NULL DEFAULT 0 CHECK (draw_count >= 0),
  winner_slot INTEGER,
  queued_at REAL NOT NULL,
  UNIQUE (group_id, round, position),
  FOREIGN KEY (group_id, left_slot) REFERENCES candidates(group_id, slot),
  FOREIGN KEY (group_id, right_slot) REFERENCES candidates(group_id, slot),
  CHECK ((state = 'decided') = (winner_slot IS NOT NULL)),
  CHECK (state != 'assigned' OR (assigned_to IS NOT NULL AND lease_expires IS NOT NULL)),
  CHECK (winner_slot IS NULL OR winner_slot IN (left_slot, right_slot))
);
CREATE INDEX comparisons_queue ON comparisons(queued_at, id) WHERE state != 'decided';
CREATE INDEX comparisons_held ON comparisons(assigned_to) WHERE state = 'assigned';
CREATE INDEX comparisons_by_group ON comparisons(group_id, state);

CREATE TABLE decisions (
  id INTEGER PRIMARY KEY AUTOINCREMENT,
  comparison_id INTEGER NOT NULL REFERENCES comparisons(id),
  annotator_id INTEGER REFERENCES annotators(id),
  answer TEXT NOT NULL CHECK (answer IN ('left', 'right', 'draw')),
  answered_at REAL NOT NULL,
  tie_break INTEGER NOT NULL DEFAULT 0 CHECK (tie_break IN (0, 1)),
  CHECK ((annotator_id IS NULL) = (tie_break = 1)),
  CHECK (tie_break = 0 OR answer != 'draw')
);
-- At most one verdict per comparison: a second answer cannot be recorded even by a buggy caller.
CREATE UNIQUE INDEX decisions_one_verdict ON decisions(comparison_id) WHERE answer != 'draw';
CREATE INDEX decisions_by_comparison ON decisions(comparison_id, annotator_id);
CREATE INDEX decisions_by_annotator ON decisions(annotator_id, id);
)sql";

// What version 2 added to version 1 (kSchemaV1): web sign-in sessions. A new store runs both;
// open() upgrades a version 1 store by running this one.
constexpr const char* kSchemaV2Sessions = R"sql(
CREATE TABLE sessions (
  token TEXT PRIMARY KEY,
  annotator_id INTEGER NOT NULL REFERENCES annotators(id),
  created_at REAL NOT NULL
) WITHOUT ROWID;
CREATE INDEX sessions_by_annotator ON sessions(annotator_id);
)sql";

double system_seconds() {
  using namespace std::chrono;
  return duration<double>(system_clock::now().time_since_epoch()).count();
}

Answer parse_answer(const std::string& text) {
  if (text == "left") return Answer::left;
  if (text == "right") return Answer::right;
  return Answer::draw;
}

ComparisonState parse_state(const std::string& text) {
  if (text == "open") return ComparisonState::open;
  if (text == "assigned") return ComparisonState::assigned;
  return ComparisonState::decided;
}

// A group's fixed facts, cached per connection (groups never change once created).
struct GroupFacts {
  std::string label;
  int candidate_count = 0;
  uint64_t seed = 0;
  std::vector<int64_t> samples;   // by slot
  std::vector<double> distances;  // by slot
};

// One row of `comparisons`, as answer() and undo_last() need it.
struct ComparisonRow {
  int64_t id = 0;
  int64_t group = 0;
  int round = 0;
  int position = 0;
  int left_slot = 0;
  int right_slot = 0;
  ComparisonState state = ComparisonState::open;
  std::optional<int64_t> assigned_to;
  double lease_expires = 0;
  int draw_count = 0;
  std::optional<int> winner_slot;
};

struct Verdict {
  int64_t id = 0;
  std::optional<int64_t> annotator;
  Answer answer = Answer::left;
  bool tie_break = false;
};

}  // namespace

const char* answer_name(Answer answer) {
  switch (answer) {
    case Answer::left:
      return "left";
    case Answer::right:
      return "right";
    case Answer::draw:
      return "draw";
  }
  return "?";
}

const char* state_name(ComparisonState state) {
  switch (state) {
    case ComparisonState::open:
      return "open";
    case ComparisonState::assigned:
      return "assigned";
    case ComparisonState::decided:
      return "decided";
  }
  return "?";
}

void StoreOptions::validate(const std::string& key_path) const {
  require(std::isfinite(busy_timeout_seconds) && busy_timeout_seconds > 0, key_path + ".busy_timeout_seconds",
          fmt::format("expected a positive number of seconds, got {}", busy_timeout_seconds));
  require(std::isfinite(active_seconds) && active_seconds > 0, key_path + ".active_seconds",
          fmt::format("expected a positive number of seconds, got {}", active_seconds));
}

int StoreProgress::done() const {
  int n = 0;
  for (const GroupProgress& g : groups) n += g.done;
  return n;
}

int StoreProgress::total() const {
  int n = 0;
  for (const GroupProgress& g : groups) n += g.total;
  return n;
}

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

struct AnnotationStore::Impl {
  Database db;
  StoreOptions options;
  std::unordered_map<int64_t, GroupFacts> facts;

  // Prepared once per connection.
  Statement find_annotator{db, "SELECT id FROM annotators WHERE name = ?1", "look up an annotator"};
  Statement annotator_name{db, "SELECT name FROM annotators WHERE id = ?1", "look up an annotator's name"};
  Statement upsert_annotator{db,
                             "INSERT INTO annotators(name, created_at, last_seen) VALUES (?1, ?2, ?2) "
                             "ON CONFLICT(name) DO UPDATE SET last_seen = excluded.last_seen",
                             "record an annotator"};
  Statement touch_annotator{db, "UPDATE annotators SET last_seen = ?2 WHERE id = ?1", "record an annotator's visit"};
  Statement find_label{db, "SELECT id FROM groups WHERE label = ?1", "look up a group label"};
  Statement insert_group{db, "INSERT INTO groups(label, seed, candidate_count, created_at) VALUES (?1, ?2, ?3, ?4)",
                         "create a group"};
  Statement insert_candidate{db, "INSERT INTO candidates(group_id, slot, sample, distance) VALUES (?1, ?2, ?3, ?4)",
                             "add a candidate to a group"};
  Statement group_row{db, "SELECT label, seed, candidate_count FROM groups WHERE id = ?1", "read a group"};
  Statement group_candidates{db, "SELECT sample, distance FROM candidates WHERE group_id = ?1 ORDER BY slot",
                             "read a group's candidates"};
  Statement all_groups{db, "SELECT id FROM groups ORDER BY id", "list the groups"};
  Statement insert_comparison{db,
                              "INSERT INTO comparisons(group_id, round, position, left_slot, right_slot, queued_at) "
                              "VALUES (?1, ?2, ?3, ?4, ?5, ?6) ON CONFLICT(group_id, round, position) DO NOTHING",
                              "open a comparison"};
  Statement held{db,
                 "SELECT id FROM comparisons WHERE state = 'assigned' AND assigned_to = ?1 "
                 "ORDER BY assigned_at DESC, id DESC LIMIT 1",
                 "find the comparison an annotator holds"};
  // Open or abandoned (lease expired), and not drawn by this annotator unless every active
  // annotator has drawn it.
  Statement next_open{db,
                      "SELECT c.id FROM comparisons c "
                      "WHERE c.state != 'decided' AND (c.state = 'open' OR c.lease_expires <= ?1) "
                      "  AND (c.draw_count = 0 "
                      "    OR NOT EXISTS (SELECT 1 FROM decisions d WHERE d.comparison_id = c.id "
                      "                   AND d.annotator_id = ?2 AND d.answer = 'draw') "
                      "    OR NOT EXISTS (SELECT 1 FROM annotators a WHERE a.last_seen >= ?3 "
                      "                   AND NOT EXISTS (SELECT 1 FROM decisions d WHERE d.comparison_id = c.id "
                      "                                   AND d.annotator_id = a.id AND d.answer = 'draw'))) "
                      "ORDER BY c.queued_at, c.id LIMIT 1",
                      "find the next open comparison"};
  Statement lease{db,
                  "UPDATE comparisons SET state = 'assigned', assigned_to = ?2, assigned_at = ?3, lease_expires = ?4 "
                  "WHERE id = ?1",
                  "lease a comparison"};
  Statement comparison_row{db,
                           "SELECT id, group_id, round, position, left_slot, right_slot, state, assigned_to, "
                           "lease_expires, draw_count, winner_slot FROM comparisons WHERE id = ?1",
                           "read a comparison"};
  Statement comparison_at{db, "SELECT id FROM comparisons WHERE group_id = ?1 AND round = ?2 AND position = ?3",
                          "find a comparison in the bracket"};
  Statement insert_decision{db,
                            "INSERT INTO decisions(comparison_id, annotator_id, answer, answered_at, tie_break) "
                            "VALUES (?1, ?2, ?3, ?4, ?5)",
                            "record a decision"};
  Statement decide{db, "UPDATE comparisons SET state = 'decided', winner_slot = ?2, draw_count = ?3 WHERE id = ?1",
                   "decide a comparison"};
  Statement requeue{db,
                    "UPDATE comparisons SET state = 'open', assigned_to = NULL, assigned_at = NULL, "
                    "lease_expires = NULL, draw_count = draw_count + 1, queued_at = ?2 WHERE id = ?1",
                    "return a drawn comparison to the queue"};
  Statement release{db,
                    "UPDATE comparisons SET state = 'open', assigned_to = NULL, assigned_at = NULL, "
                    "lease_expires = NULL WHERE id = ?1",
                    "release a comparison"};
  Statement reassign{db,
                     "UPDATE comparisons SET state = 'assigned', winner_slot = NULL, assigned_to = ?2, "
                     "assigned_at = ?3, lease_expires = ?4, draw_count = ?5 WHERE id = ?1",
                     "hand a comparison back after an undo"};
  Statement draws_by{db,
                     "SELECT count(*) FROM decisions WHERE comparison_id = ?1 AND annotator_id = ?2 "
                     "AND answer = 'draw'",
                     "count an annotator's draws"};
  Statement answers_to{db, "SELECT count(*) FROM decisions WHERE comparison_id = ?1", "count a comparison's answers"};
  Statement verdict_of{db,
                       "SELECT id, annotator_id, answer, tie_break FROM decisions "
                       "WHERE comparison_id = ?1 AND answer != 'draw'",
                       "read a comparison's verdict"};
  Statement last_decision{db,
                          "SELECT id, comparison_id, answer FROM decisions WHERE annotator_id = ?1 "
                          "ORDER BY id DESC LIMIT 1",
                          "find an annotator's last answer"};
  Statement group_decided{db,
                          "SELECT round, position, winner_slot FROM comparisons "
                          "WHERE group_id = ?1 AND state = 'decided' ORDER BY round, position",
                          "read a group's results"};
  Statement delete_comparison{db, "DELETE FROM comparisons WHERE id = ?1", "withdraw a comparison"};
  Statement delete_decision{db, "DELETE FROM decisions WHERE id = ?1", "take back a decision"};
  Statement assignment_row{db,
                           "SELECT c.group_id, g.label, c.round, l.sample, r.sample, c.lease_expires "
                           "FROM comparisons c JOIN groups g ON g.id = c.group_id "
                           "JOIN candidates l ON l.group_id = c.group_id AND l.slot = c.left_slot "
                           "JOIN candidates r ON r.group_id = c.group_id AND r.slot = c.right_slot WHERE c.id = ?1",
                           "read an assignment"};
  Statement list_comparisons{db,
                             "SELECT c.id, c.group_id, c.round, c.position, l.sample, r.sample, c.state, "
                             "coalesce(a.name, ''), coalesce(c.assigned_at, 0), c.draw_count, w.sample "
                             "FROM comparisons c "
                             "JOIN candidates l ON l.group_id = c.group_id AND l.slot = c.left_slot "
                             "JOIN candidates r ON r.group_id = c.group_id AND r.slot = c.right_slot "
                             "LEFT JOIN candidates w ON w.group_id = c.group_id AND w.slot = c.winner_slot "
                             "LEFT JOIN annotators a ON a.id = c.assigned_to "
                             "WHERE ?1 IS NULL OR c.group_id = ?1 ORDER BY c.id",
                             "list comparisons"};
  Statement list_draws{db,
                       "SELECT d.comparison_id, a.name FROM decisions d JOIN annotators a ON a.id = d.annotator_id "
                       "WHERE d.answer = 'draw' ORDER BY d.id",
                       "list draws"};
  Statement list_decisions{db,
                           "SELECT d.id, d.comparison_id, coalesce(a.name, ''), d.answer, d.answered_at, d.tie_break "
                           "FROM decisions d LEFT JOIN annotators a ON a.id = d.annotator_id ORDER BY d.id",
                           "list decisions"};
  Statement group_progress{db,
                           "SELECT g.id, g.label, g.candidate_count, "
                           "  (SELECT count(*) FROM comparisons c WHERE c.group_id = g.id AND c.state = 'decided'), "
                           "  (SELECT count(*) FROM decisions d JOIN comparisons c ON c.id = d.comparison_id "
                           "   WHERE c.group_id = g.id AND d.tie_break = 1), "
                           "  (SELECT s.sample FROM comparisons c JOIN candidates s "
                           "   ON s.group_id = c.group_id AND s.slot = c.winner_slot "
                           "   WHERE c.group_id = g.id AND c.state = 'decided' ORDER BY c.round DESC LIMIT 1) "
                           "FROM groups g ORDER BY g.id",
                           "summarise the groups"};
  Statement annotator_progress{
      db,
      "SELECT a.name, coalesce(sum(d.answer != 'draw'), 0), coalesce(sum(d.answer = 'draw'), 0), "
      "a.last_seen FROM annotators a LEFT JOIN decisions d ON d.annotator_id = a.id "
      "GROUP BY a.id ORDER BY a.name",
      "summarise the annotators"};
  Statement live_leases{db,
                        "SELECT a.name, count(*) FROM comparisons c JOIN annotators a ON a.id = c.assigned_to "
                        "WHERE c.state = 'assigned' AND c.lease_expires > ?1 GROUP BY a.id",
                        "count the comparisons annotators hold"};
  Statement find_sample{db, "SELECT 1 FROM candidates WHERE sample = ?1 LIMIT 1", "look up a candidate sample"};
  Statement insert_session{db, "INSERT INTO sessions(token, annotator_id, created_at) VALUES (?1, ?2, ?3)",
                           "record a sign-in session"};
  Statement find_session{db,
                         "SELECT a.name FROM sessions s JOIN annotators a ON a.id = s.annotator_id WHERE s.token = ?1",
                         "look up a sign-in session"};
  Statement count_sessions{db, "SELECT count(*) FROM sessions WHERE annotator_id = ?1",
                           "count an annotator's sessions"};
  Statement delete_sessions{db, "DELETE FROM sessions WHERE annotator_id = ?1", "end an annotator's sessions"};
  Statement release_held{db,
                         "UPDATE comparisons SET state = 'open', assigned_to = NULL, assigned_at = NULL, "
                         "lease_expires = NULL WHERE state = 'assigned' AND assigned_to = ?1",
                         "release an annotator's comparisons"};
  Statement finished{db,
                     "SELECT (SELECT count(*) FROM comparisons WHERE state = 'decided') = "
                     "(SELECT coalesce(sum(candidate_count - 1), 0) FROM groups)",
                     "check whether every tournament is finished"};
  Statement verdicts{db,
                     "SELECT c.group_id, g.label, l.sample, r.sample, c.winner_slot = c.left_slot, d.tie_break "
                     "FROM decisions d JOIN comparisons c ON c.id = d.comparison_id "
                     "JOIN groups g ON g.id = c.group_id "
                     "JOIN candidates l ON l.group_id = c.group_id AND l.slot = c.left_slot "
                     "JOIN candidates r ON r.group_id = c.group_id AND r.slot = c.right_slot "
                     "WHERE d.answer != 'draw' ORDER BY c.group_id, d.id",
                     "read the decided comparisons"};

  Impl(Database database, StoreOptions store_options) : db(std::move(database)), options(std::move(store_options)) {}

  double now() const { return options.clock ? options.clock() : system_seconds(); }

  [[noreturn]] void fail(const std::string& what) const { throw Error(db.path(), what); }

  std::optional<int64_t> annotator_id(const std::string& name) {
    Query q(find_annotator);
    q.bind(1, name);
    if (!q.next()) return std::nullopt;
    return q.int64(0);
  }

  int64_t require_annotator(const std::string& name) {
    std::optional<int64_t> id = annotator_id(name);
    if (!id) fail(fmt::format("unknown annotator '{}': it has never asked for a comparison", name));
    Query(touch_annotator).bind(1, *id).bind(2, now()).run();
    return *id;
  }

  int64_t upsert(const std::string& name) {
    if (name.empty()) fail("the annotator name is empty");
    Query(upsert_annotator).bind(1, name).bind(2, now()).run();
    return *annotator_id(name);
  }

  std::string name_of(std::optional<int64_t> id) {
    if (!id) return std::string();
    Query q(annotator_name);
    q.bind(1, *id);
    return q.next() ? q.text(0) : fmt::format("#{}", *id);
  }

  const GroupFacts& group_facts(int64_t group) {
    auto it = facts.find(group);
    if (it != facts.end()) return it->second;
    GroupFacts f;
    {
      Query q(group_row);
      q.bind(1, group);
      if (!q.next()) fail(fmt::format("group {} does not exist", group));
      f.label = q.text(0);
      f.seed = static_cast<uint64_t>(q.int64(1));
      f.candidate_count = q.integer(2);
    }
    {
      Query q(group_candidates);
      q.bind(1, group);
      while (q.next()) {
        f.samples.push_back(q.int64(0));
        f.distances.push_back(q.real(1));
      }
    }
    if (static_cast<int>(f.samples.size()) != f.candidate_count) {
      fail(fmt::format("group {} lists {} candidates but has {}", group, f.candidate_count, f.samples.size()));
    }
    return facts.emplace(group, std::move(f)).first->second;
  }

  std::optional<ComparisonRow> read_comparison(int64_t id) {
    Query q(comparison_row);
    q.bind(1, id);
    if (!q.next()) return std::nullopt;
    ComparisonRow row;
    row.id = q.int64(0);
    row.group = q.int64(1);
    row.round = q.integer(2);
    row.position = q.integer(3);
    row.left_slot = q.integer(4);
    row.right_slot = q.integer(5);
    row.state = parse_state(q.text(6));
    if (!q.is_null(7)) row.assigned_to = q.int64(7);
    row.lease_expires = q.is_null(8) ? 0 : q.real(8);
    row.draw_count = q.integer(9);
    if (!q.is_null(10)) row.winner_slot = q.integer(10);
    return row;
  }

  ComparisonRow require_comparison(int64_t id) {
    std::optional<ComparisonRow> row = read_comparison(id);
    if (!row) fail(fmt::format("comparison {} does not exist (or was withdrawn by an undo)", id));
    return *row;
  }

  std::optional<Verdict> read_verdict(int64_t comparison) {
    Query q(verdict_of);
    q.bind(1, comparison);
    if (!q.next()) return std::nullopt;
    Verdict v;
    v.id = q.int64(0);
    if (!q.is_null(1)) v.annotator = q.int64(1);
    v.answer = parse_answer(q.text(2));
    v.tie_break = q.int64(3) != 0;
    return v;
  }

  Assignment read_assignment(int64_t comparison) {
    Query q(assignment_row);
    q.bind(1, comparison);
    if (!q.next()) fail(fmt::format("comparison {} does not exist", comparison));
    Assignment a;
    a.comparison = comparison;
    a.group = q.int64(0);
    a.label = q.text(1);
    a.round = q.integer(2);
    a.left = q.int64(3);
    a.right = q.int64(4);
    a.lease_expires = q.is_null(5) ? 0 : q.real(5);
    return a;
  }

  // The group's tournament as decided so far.
  Tournament tournament(int64_t group) {
    const GroupFacts& f = group_facts(group);
    Tournament t(f.candidate_count, f.seed);
    Query q(group_decided);
    q.bind(1, group);
    while (q.next()) t.decide(q.integer(0), q.integer(1), q.integer(2));
    return t;
  }

  // Opens every comparison the group's tournament can hold now and does not have yet; returns
  // their ids.
  std::vector<int64_t> open_ready(int64_t group, const Tournament& t) {
    std::vector<int64_t> opened;
    const double time = now();
    for (const Match& m : t.ready()) {
      Query(insert_comparison)
          .bind(1, group)
          .bind(2, m.round)
          .bind(3, m.position)
          .bind(4, m.left)
          .bind(5, m.right)
          .bind(6, time)
          .run();
      if (db.changes() == 1) opened.push_back(db.last_insert_id());
    }
    return opened;
  }

  // Records the winner of `row`, then opens what the tournament can hold next.
  AnswerResult settle(const ComparisonRow& row, int winner_slot, int draw_count, AnswerStatus status) {
    Query(decide).bind(1, row.id).bind(2, winner_slot).bind(3, draw_count).run();
    Tournament t = tournament(row.group);
    const GroupFacts& f = group_facts(row.group);
    AnswerResult result;
    result.status = status;
    result.winner = f.samples[static_cast<size_t>(winner_slot)];
    result.opened = open_ready(row.group, t);
    if (std::optional<int> champion = t.champion()) result.champion = f.samples[static_cast<size_t>(*champion)];
    return result;
  }

  // Withdraws the comparison that `row`'s winner advanced to, unless it has been answered.
  void withdraw_next(const ComparisonRow& row, const std::string& undoing) {
    const GroupFacts& f = group_facts(row.group);
    const Tournament shape(f.candidate_count, f.seed);
    if (row.round == shape.round_count()) return;  // the final feeds nothing
    int64_t next = 0;
    {
      Query find(comparison_at);
      find.bind(1, row.group).bind(2, row.round + 1).bind(3, row.position / 2);
      if (!find.next()) return;
      next = find.int64(0);
    }
    int64_t answers = 0;
    {
      Query count(answers_to);
      count.bind(1, next);
      count.next();
      answers = count.int64(0);
    }
    if (answers > 0) {
      fail(
          fmt::format("cannot undo {} to comparison {}: comparison {} (round {}), which its winner advanced to, has "
                      "already been answered",
                      undoing, row.id, next, row.round + 1));
    }
    Query(delete_comparison).bind(1, next).run();
  }
};

AnnotationStore::AnnotationStore(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
AnnotationStore::AnnotationStore(AnnotationStore&&) noexcept = default;
AnnotationStore& AnnotationStore::operator=(AnnotationStore&&) noexcept = default;
AnnotationStore::~AnnotationStore() = default;

const std::string& AnnotationStore::path() const { return impl_->db.path(); }

AnnotationStore AnnotationStore::open(const std::string& path, const StoreOptions& options) {
  options.validate();
  sqlite::DatabaseOptions db_options;
  db_options.busy_timeout_seconds = options.busy_timeout_seconds;
  Database db = Database::open(path, db_options);

  // WAL: readers see a consistent snapshot while one writer commits; survives a killed process.
  db.enable_wal();
  // NORMAL is durable against a killed process in WAL mode; only a power cut may lose the last
  // commits, never consistency.
  db.exec("PRAGMA synchronous = NORMAL", "set the synchronous mode");

  {
    Transaction tx(db, Transaction::Kind::write, "check the schema");
    int64_t table_count = 0;
    bool has_meta = false;
    {
      Statement tables(db, "SELECT count(*), coalesce(sum(name = 'meta'), 0) FROM sqlite_master WHERE type = 'table'",
                       "list the tables");
      Query q(tables);
      q.next();
      table_count = q.int64(0);
      has_meta = q.int64(1) > 0;
    }
    if (!has_meta && table_count > 0) {
      throw Error(path, "is an SQLite database but not an annotation store (it has tables but no meta table)");
    }
    if (!has_meta) {
      db.exec(kSchemaV1, "create the schema");
      db.exec(kSchemaV2Sessions, "create the sessions table");
      db.exec(fmt::format("INSERT INTO meta(key, value) VALUES ('application', '{}'), ('schema_version', '{}')",
                          kApplication, kSchemaVersion),
              "record the schema version");
    } else {
      std::map<std::string, std::string> values;
      {
        Statement meta(db, "SELECT key, value FROM meta", "read the meta table");
        Query m(meta);
        while (m.next()) values[m.text(0)] = m.text(1);
      }
      if (values["application"] != kApplication) {
        throw Error(path, fmt::format("is not an annotation store (meta.application is '{}', expected '{}')",
                                      values["application"], kApplication));
      }
      if (values["schema_version"] == "1") {
        db.exec(kSchemaV2Sessions, "upgrade the schema from version 1 to 2 (web sign-in sessions)");
        db.exec("UPDATE meta SET value = '2' WHERE key = 'schema_version'", "record schema version 2");
        values["schema_version"] = "2";
      }
      if (values["schema_version"] != std::to_string(kSchemaVersion)) {
        throw Error(path, fmt::format("has annotation schema version {}, but this build reads version {}",
                                      values["schema_version"], kSchemaVersion));
      }
    }
    tx.commit();
  }
  return AnnotationStore(std::make_unique<Impl>(std::move(db), options));
}

int64_t AnnotationStore::create_group(const std::string& label, const std::vector<int64_t>& candidates,
                                      const std::vector<double>& distances, uint64_t seed) {
  Impl& s = *impl_;
  const std::string call = fmt::format("create_group('{}')", label);
  if (label.empty()) s.fail("create_group: the group label (the human expression's name) is empty");
  if (candidates.size() < 2) s.fail(fmt::format("{}: needs at least 2 candidates, got {}", call, candidates.size()));
  if (distances.size() != candidates.size()) {
    s.fail(fmt::format("{}: {} candidates but {} distances", call, candidates.size(), distances.size()));
  }
  std::set<int64_t> seen;
  for (size_t i = 0; i < candidates.size(); ++i) {
    if (!seen.insert(candidates[i]).second) {
      s.fail(fmt::format("{}: sample {} is listed twice (candidate {})", call, candidates[i], i));
    }
    if (!std::isfinite(distances[i])) {
      s.fail(fmt::format("{}: the distance of candidate {} (sample {}) is {}", call, i, candidates[i], distances[i]));
    }
  }
  const Tournament t(static_cast<int>(candidates.size()), seed);

  Transaction tx(s.db, Transaction::Kind::write, "create a group");
  {
    Query q(s.find_label);
    q.bind(1, label);
    if (q.next()) s.fail(fmt::format("{}: a group with this label already exists (group {})", call, q.int64(0)));
  }
  Query(s.insert_group)
      .bind(1, label)
      .bind(2, static_cast<int64_t>(seed))
      .bind(3, static_cast<int64_t>(candidates.size()))
      .bind(4, s.now())
      .run();
  const int64_t group = s.db.last_insert_id();
  for (size_t i = 0; i < candidates.size(); ++i) {
    Query(s.insert_candidate)
        .bind(1, group)
        .bind(2, static_cast<int64_t>(i))
        .bind(3, candidates[i])
        .bind(4, distances[i])
        .run();
  }
  s.open_ready(group, t);
  tx.commit();
  return group;
}

GroupInfo AnnotationStore::group(int64_t id) const {
  Impl& s = *impl_;
  Transaction tx(s.db, Transaction::Kind::read, "read a group");
  const GroupFacts& f = s.group_facts(id);
  GroupInfo info;
  info.id = id;
  info.label = f.label;
  info.candidates = f.samples;
  info.distances = f.distances;
  info.seed = f.seed;
  tx.commit();
  return info;
}

std::vector<GroupInfo> AnnotationStore::groups() const {
  std::vector<int64_t> ids;
  {
    Transaction tx(impl_->db, Transaction::Kind::read, "list the groups");
    Query q(impl_->all_groups);
    while (q.next()) ids.push_back(q.int64(0));
  }
  std::vector<GroupInfo> out;
  for (int64_t id : ids) out.push_back(group(id));
  return out;
}

void AnnotationStore::register_annotator(const std::string& name) {
  Impl& s = *impl_;
  Transaction tx(s.db, Transaction::Kind::write, "register an annotator");
  s.upsert(name);
  tx.commit();
}

std::optional<Assignment> AnnotationStore::next_comparison(const std::string& annotator, double lease_seconds) {
  Impl& s = *impl_;
  if (!std::isfinite(lease_seconds) || lease_seconds <= 0) {
    s.fail(fmt::format("next_comparison('{}'): lease_seconds must be a positive number, got {}", annotator,
                       lease_seconds));
  }
  Transaction tx(s.db, Transaction::Kind::write, "hand out a comparison");
  const int64_t me = s.upsert(annotator);
  const double now = s.now();
  std::optional<int64_t> chosen;
  {
    Query q(s.held);
    q.bind(1, me);
    if (q.next()) chosen = q.int64(0);
  }
  if (!chosen) {
    Query q(s.next_open);
    q.bind(1, now).bind(2, me).bind(3, now - s.options.active_seconds);
    if (q.next()) chosen = q.int64(0);
  }
  if (!chosen) {
    tx.commit();  // keeps last_seen: the annotator is active even when there is nothing to do
    return std::nullopt;
  }
  Query(s.lease).bind(1, *chosen).bind(2, me).bind(3, now).bind(4, now + lease_seconds).run();
  Assignment a = s.read_assignment(*chosen);
  tx.commit();
  return a;
}

AnswerResult AnnotationStore::answer(int64_t comparison, const std::string& annotator, Answer answer) {
  Impl& s = *impl_;
  Transaction tx(s.db, Transaction::Kind::write, "record an answer");
  const int64_t me = s.require_annotator(annotator);
  const ComparisonRow row = s.require_comparison(comparison);
  if (row.state == ComparisonState::decided) {
    const std::optional<Verdict> v = s.read_verdict(comparison);
    const std::string by = !v             ? std::string("someone")
                           : v->tie_break ? std::string("the tie-break")
                                          : fmt::format("'{}'", s.name_of(v->annotator));
    s.fail(fmt::format("comparison {} is already decided ({} chose {}); a comparison takes one answer", comparison, by,
                       v ? answer_name(v->answer) : "?"));
  }
  if (row.state != ComparisonState::assigned || row.assigned_to != me) {
    const std::string holder = row.state == ComparisonState::open
                                   ? std::string("it is back in the queue")
                                   : fmt::format("it is leased to '{}'", s.name_of(row.assigned_to));
    s.fail(fmt::format("annotator '{}' does not hold comparison {} ({}); ask next_comparison() for work", annotator,
                       comparison, holder));
  }

  const double now = s.now();
  AnswerResult result;
  if (answer != Answer::draw) {
    Query(s.insert_decision)
        .bind(1, comparison)
        .bind(2, me)
        .bind(3, std::string(answer_name(answer)))
        .bind(4, now)
        .bind(5, 0)
        .run();
    const int winner = answer == Answer::left ? row.left_slot : row.right_slot;
    result = s.settle(row, winner, row.draw_count, AnswerStatus::decided);
  } else {
    bool drew_before = false;
    {
      Query count(s.draws_by);
      count.bind(1, comparison).bind(2, me);
      count.next();
      drew_before = count.int64(0) > 0;
    }
    Query(s.insert_decision).bind(1, comparison).bind(2, me).bind(3, std::string("draw")).bind(4, now).bind(5, 0).run();
    if (!drew_before) {
      Query(s.requeue).bind(1, comparison).bind(2, now).run();
      result.status = AnswerStatus::requeued;
    } else {
      // The comparison came back to someone who already drew it: the smaller distance to y0 wins.
      const GroupFacts& f = s.group_facts(row.group);
      const bool left_wins =
          f.distances[static_cast<size_t>(row.left_slot)] <= f.distances[static_cast<size_t>(row.right_slot)];
      Query(s.insert_decision)
          .bind(1, comparison)
          .bind_null(2)
          .bind(3, std::string(left_wins ? "left" : "right"))
          .bind(4, now)
          .bind(5, 1)
          .run();
      result = s.settle(row, left_wins ? row.left_slot : row.right_slot, row.draw_count + 1, AnswerStatus::tie_break);
    }
  }
  tx.commit();
  return result;
}

void AnnotationStore::release(int64_t comparison, const std::string& annotator) {
  Impl& s = *impl_;
  Transaction tx(s.db, Transaction::Kind::write, "release a comparison");
  const int64_t me = s.require_annotator(annotator);
  const ComparisonRow row = s.require_comparison(comparison);
  if (row.state != ComparisonState::assigned || row.assigned_to != me) {
    s.fail(fmt::format("annotator '{}' cannot release comparison {}: it does not hold it (the comparison is {})",
                       annotator, comparison, state_name(row.state)));
  }
  Query(s.release).bind(1, comparison).run();
  tx.commit();
}

Assignment AnnotationStore::undo_last(const std::string& annotator, double lease_seconds) {
  Impl& s = *impl_;
  if (!std::isfinite(lease_seconds) || lease_seconds <= 0) {
    s.fail(fmt::format("undo_last('{}'): lease_seconds must be a positive number, got {}", annotator, lease_seconds));
  }
  Transaction tx(s.db, Transaction::Kind::write, "undo an answer");
  const int64_t me = s.require_annotator(annotator);
  int64_t decision = 0, comparison = 0;
  Answer answered = Answer::left;
  {
    Query q(s.last_decision);
    q.bind(1, me);
    if (!q.next()) s.fail(fmt::format("annotator '{}' has no answer to undo", annotator));
    decision = q.int64(0);
    comparison = q.int64(1);
    answered = parse_answer(q.text(2));
  }
  const ComparisonRow row = s.require_comparison(comparison);
  const double now = s.now();
  int draw_count = row.draw_count;
  if (answered != Answer::draw) {
    s.withdraw_next(row, fmt::format("annotator '{}''s answer", annotator));
  } else {
    const std::string undoing = fmt::format("annotator '{}''s draw", annotator);
    if (row.state == ComparisonState::decided) {
      const std::optional<Verdict> v = s.read_verdict(comparison);
      if (!v || !v->tie_break || v->id < decision) {
        s.fail(fmt::format("cannot undo {} on comparison {}: '{}' has decided it since", undoing, comparison,
                           v ? s.name_of(v->annotator) : std::string("someone")));
      }
      // This draw triggered the tie-break: take both back.
      s.withdraw_next(row, undoing);
      Query(s.delete_decision).bind(1, v->id).run();
    } else if (row.state == ComparisonState::assigned && row.assigned_to != me && row.lease_expires > now) {
      s.fail(fmt::format("cannot undo {} on comparison {}: annotator '{}' holds it now", undoing, comparison,
                         s.name_of(row.assigned_to)));
    }
    draw_count = std::max(0, draw_count - 1);
  }
  Query(s.delete_decision).bind(1, decision).run();
  Query(s.reassign).bind(1, comparison).bind(2, me).bind(3, now).bind(4, now + lease_seconds).bind(5, draw_count).run();
  Assignment a = s.read_assignment(comparison);
  tx.commit();
  return a;
}

std::vector<ComparisonRecord> AnnotationStore::comparisons(std::optional<int64_t> group) const {
  Impl& s = *impl_;
  Transaction tx(s.db, Transaction::Kind::read, "list comparisons");
  std::map<int64_t, std::vector<std::string>> drawn;
  {
    Query q(s.list_draws);
    while (q.next()) drawn[q.int64(0)].push_back(q.text(1));
  }
  std::vector<ComparisonRecord> out;
  Query q(s.list_comparisons);
  if (group) {
    q.bind(1, *group);
  } else {
    q.bind_null(1);
  }
  while (q.next()) {
    ComparisonRecord c;
    c.id = q.int64(0);
    c.group = q.int64(1);
    c.round = q.integer(2);
    c.position = q.integer(3);
    c.left = q.int64(4);
    c.right = q.int64(5);
    c.state = parse_state(q.text(6));
    c.assigned_to = q.text(7);
    c.assigned_at = q.real(8);
    c.draw_count = q.integer(9);
    if (!q.is_null(10)) c.winner = q.int64(10);
    c.drawn_by = drawn[c.id];
    out.push_back(std::move(c));
  }
  return out;
}

std::vector<DecisionRecord> AnnotationStore::decisions() const {
  Impl& s = *impl_;
  Transaction tx(s.db, Transaction::Kind::read, "list decisions");
  std::vector<DecisionRecord> out;
  Query q(s.list_decisions);
  while (q.next()) {
    DecisionRecord d;
    d.id = q.int64(0);
    d.comparison = q.int64(1);
    d.annotator = q.text(2);
    d.answer = parse_answer(q.text(3));
    d.time = q.real(4);
    d.tie_break = q.int64(5) != 0;
    out.push_back(std::move(d));
  }
  return out;
}

StoreProgress AnnotationStore::progress() const {
  Impl& s = *impl_;
  Transaction tx(s.db, Transaction::Kind::read, "summarise progress");
  StoreProgress p;
  {
    Query q(s.group_progress);
    while (q.next()) {
      GroupProgress g;
      g.group = q.int64(0);
      g.label = q.text(1);
      g.total = q.integer(2) - 1;
      g.done = q.integer(3);
      g.tie_breaks = q.integer(4);
      if (g.done == g.total && !q.is_null(5)) g.champion = q.int64(5);
      p.groups.push_back(std::move(g));
    }
  }
  {
    Query q(s.annotator_progress);
    while (q.next()) {
      AnnotatorProgress a;
      a.name = q.text(0);
      a.decided = q.integer(1);
      a.draws = q.integer(2);
      a.last_seen = q.real(3);
      p.annotators.push_back(std::move(a));
    }
  }
  {
    Query q(s.live_leases);
    q.bind(1, s.now());
    while (q.next()) {
      const std::string name = q.text(0);
      const int n = q.integer(1);
      p.held += n;
      for (AnnotatorProgress& a : p.annotators)
        if (a.name == name) a.holding = n;
    }
  }
  return p;
}

bool AnnotationStore::finished() const {
  Query q(impl_->finished);
  q.next();
  return q.int64(0) != 0;
}

std::vector<Triplet> AnnotationStore::triplets(bool include_derived) const {
  Impl& s = *impl_;
  struct GroupResults {
    std::string label;
    std::vector<MatchResult> results;
  };
  std::map<int64_t, GroupResults> groups;
  {
    Transaction tx(s.db, Transaction::Kind::read, "read the triplets");
    Query q(s.verdicts);
    while (q.next()) {
      GroupResults& g = groups[q.int64(0)];
      g.label = q.text(1);
      const int64_t left = q.int64(2), right = q.int64(3);
      const bool left_won = q.int64(4) != 0;
      g.results.push_back({left_won ? left : right, left_won ? right : left, q.int64(5) != 0});
    }
  }
  std::vector<Triplet> out;
  for (const auto& [id, g] : groups) {
    for (const Ordering& o : derive_triplets(g.results)) {
      if (o.derived && !include_derived) continue;
      out.push_back({id, g.label, o.positive, o.negative, o.derived, o.tie_break});
    }
  }
  return out;
}

bool AnnotationStore::has_comparison(int64_t id) const { return impl_->read_comparison(id).has_value(); }

bool AnnotationStore::has_sample(int64_t sample) const {
  Query q(impl_->find_sample);
  q.bind(1, sample);
  return q.next();
}

void AnnotationStore::add_session(const std::string& token, const std::string& annotator) {
  Impl& s = *impl_;
  if (token.size() < 16) s.fail("add_session: the session token must have at least 16 characters");
  Transaction tx(s.db, Transaction::Kind::write, "record a sign-in session");
  const int64_t id = s.upsert(annotator);
  Query(s.insert_session).bind(1, token).bind(2, id).bind(3, s.now()).run();
  tx.commit();
}

std::optional<std::string> AnnotationStore::session_annotator(const std::string& token) const {
  Query q(impl_->find_session);
  q.bind(1, token);
  if (!q.next()) return std::nullopt;
  return q.text(0);
}

bool AnnotationStore::has_session(const std::string& annotator) const {
  Impl& s = *impl_;
  const std::optional<int64_t> id = s.annotator_id(annotator);
  if (!id) return false;
  Query q(s.count_sessions);
  q.bind(1, *id);
  q.next();
  return q.int64(0) > 0;
}

SessionsEnded AnnotationStore::end_sessions(const std::string& annotator) {
  Impl& s = *impl_;
  Transaction tx(s.db, Transaction::Kind::write, "end an annotator's sessions");
  SessionsEnded out;
  const std::optional<int64_t> id = s.annotator_id(annotator);
  if (!id) s.fail(fmt::format("end_sessions: unknown annotator '{}'", annotator));
  Query(s.delete_sessions).bind(1, *id).run();
  out.sessions = s.db.changes();
  Query(s.release_held).bind(1, *id).run();
  out.released = s.db.changes();
  tx.commit();
  return out;
}

void AnnotationStore::export_csv(const std::string& path, bool include_derived) const {
  const std::vector<Triplet> rows = triplets(include_derived);
  write_file_atomically(path, [&](std::ostream& out) {
    out << "group,anchor,positive,negative,derived,tie_break\n";
    for (const Triplet& t : rows) {
      out << t.group << ',' << csv_field(t.anchor) << ',' << t.positive << ',' << t.negative << ','
          << (t.derived ? 1 : 0) << ',' << (t.tie_break ? 1 : 0) << '\n';
    }
  });
}

}  // namespace retarget
