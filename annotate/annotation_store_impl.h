// The annotation store's private parts, internal to the store: the implementation files of
// AnnotationStore (annotate/annotation_store.h) include it, nothing else does. It holds the
// connection's prepared statements and the lookups those files share:
//   annotation_store.cpp           answer and state names, options, the shared lookups, groups
//   annotation_store_schema.cpp    the SQL schema, open() and the upgrade from older versions
//   annotation_store_queue.cpp     the tournament queue (create_group, next_comparison, answer,
//                                  release, undo_last) and what it reports (comparisons,
//                                  decisions, progress, finished, triplets)
//   annotation_store_sessions.cpp  the web tool's sign-in sessions
//   annotation_store_export.cpp    the triplets as CSV
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "annotate/annotation_store.h"
#include "annotate/sqlite.h"
#include "annotate/tournament.h"
#include "core/error.h"

namespace retarget {

namespace store_internal {

// The system clock: seconds since the Unix epoch.
double system_seconds();

// The stored text of an answer or a comparison state (the schema's CHECKs admit no other values).
Answer parse_answer(const std::string& text);
ComparisonState parse_state(const std::string& text);

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

// The left/right answer that decided a comparison, as stored.
struct Verdict {
  int64_t id = 0;
  std::optional<int64_t> annotator;
  Answer answer = Answer::left;
  bool tie_break = false;
};

}  // namespace store_internal

struct AnnotationStore::Impl {
  using Database = sqlite::Database;
  using Statement = sqlite::Statement;
  using GroupFacts = store_internal::GroupFacts;
  using ComparisonRow = store_internal::ComparisonRow;
  using Verdict = store_internal::Verdict;

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
                     "SELECT c.group_id, g.label, l.sample, r.sample, c.winner_slot = c.left_slot, d.tie_break, "
                     "coalesce(a.name, '') "
                     "FROM decisions d JOIN comparisons c ON c.id = d.comparison_id "
                     "JOIN groups g ON g.id = c.group_id "
                     "JOIN candidates l ON l.group_id = c.group_id AND l.slot = c.left_slot "
                     "JOIN candidates r ON r.group_id = c.group_id AND r.slot = c.right_slot "
                     "LEFT JOIN annotators a ON a.id = d.annotator_id "
                     "WHERE d.answer != 'draw' ORDER BY c.group_id, d.id",
                     "read the decided comparisons"};

  Impl(Database database, StoreOptions store_options) : db(std::move(database)), options(std::move(store_options)) {}

  double now() const { return options.clock ? options.clock() : store_internal::system_seconds(); }

  [[noreturn]] void fail(const std::string& what) const { throw Error(db.path(), what); }

  // --- shared lookups (annotation_store.cpp) ---

  // The id of annotator `name`; nullopt when it is not registered.
  std::optional<int64_t> annotator_id(const std::string& name);

  // The id of a registered annotator, marked as seen now; fails for an unknown one.
  int64_t require_annotator(const std::string& name);

  // Registers `name` (non-empty) or marks it as seen now; returns its id.
  int64_t upsert(const std::string& name);

  // An annotator's name for messages: empty for none (a tie-break), "#<id>" for an unknown id.
  std::string name_of(std::optional<int64_t> id);

  // The group's fixed facts, read once per connection; fails for an unknown group.
  const GroupFacts& group_facts(int64_t group);

  // The comparison as stored; nullopt when it does not exist.
  std::optional<ComparisonRow> read_comparison(int64_t id);

  // --- the tournament queue (annotation_store_queue.cpp) ---

  // Fails for a comparison that does not exist (or was withdrawn by an undo).
  ComparisonRow require_comparison(int64_t id);

  // The comparison's left/right answer (a person's or the tie-break), if decided.
  std::optional<Verdict> read_verdict(int64_t comparison);

  // The comparison as handed to an annotator; fails when it does not exist.
  Assignment read_assignment(int64_t comparison);

  // The group's tournament as decided so far.
  Tournament tournament(int64_t group);

  // Opens every comparison the group's tournament can hold now and does not have yet; returns
  // their ids.
  std::vector<int64_t> open_ready(int64_t group, const Tournament& t);

  // Records the winner of `row`, then opens what the tournament can hold next.
  AnswerResult settle(const ComparisonRow& row, int winner_slot, int draw_count, AnswerStatus status);

  // Withdraws the comparison that `row`'s winner advanced to, unless it has been answered.
  void withdraw_next(const ComparisonRow& row, const std::string& undoing);
};

}  // namespace retarget
