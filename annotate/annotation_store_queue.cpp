// The tournament queue of AnnotationStore: groups' comparisons handed out under leases, answered
// (draws requeued or settled by the tie-break), released and undone, and the reports on them.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <utility>

#include "annotate/annotation_store.h"
#include "annotate/annotation_store_impl.h"
#include "annotate/tournament.h"
#include "core/error.h"

namespace retarget {

using sqlite::Query;
using sqlite::Transaction;
using store_internal::ComparisonRow;
using store_internal::GroupFacts;
using store_internal::parse_answer;
using store_internal::parse_state;
using store_internal::Verdict;

ComparisonRow AnnotationStore::Impl::require_comparison(int64_t id) {
  std::optional<ComparisonRow> row = read_comparison(id);
  if (!row) fail(fmt::format("comparison {} does not exist (or was withdrawn by an undo)", id));
  return *row;
}

std::optional<Verdict> AnnotationStore::Impl::read_verdict(int64_t comparison) {
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

Assignment AnnotationStore::Impl::read_assignment(int64_t comparison) {
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

Tournament AnnotationStore::Impl::tournament(int64_t group) {
  const GroupFacts& f = group_facts(group);
  Tournament t(f.candidate_count, f.seed);
  Query q(group_decided);
  q.bind(1, group);
  while (q.next()) t.decide(q.integer(0), q.integer(1), q.integer(2));
  return t;
}

std::vector<int64_t> AnnotationStore::Impl::open_ready(int64_t group, const Tournament& t) {
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

AnswerResult AnnotationStore::Impl::settle(const ComparisonRow& row, int winner_slot, int draw_count,
                                           AnswerStatus status) {
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

void AnnotationStore::Impl::withdraw_next(const ComparisonRow& row, const std::string& undoing) {
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
    s.fail(fmt::format("annotator '{}' does not hold comparison {} ({}); ask for the next comparison to go on",
                       annotator, comparison, holder));
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
    std::map<std::pair<int64_t, int64_t>, std::string> decided_by;  // (winner, loser) -> the first annotator
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
      g.decided_by.emplace(std::pair{g.results.back().winner, g.results.back().loser}, q.text(6));
    }
  }
  std::vector<Triplet> out;
  for (const auto& [id, g] : groups) {
    for (const Ordering& o : derive_triplets(g.results)) {
      if (o.derived && !include_derived) continue;
      const std::string by = o.derived ? "" : g.decided_by.at({o.positive, o.negative});
      out.push_back({id, g.label, o.positive, o.negative, o.derived, o.tie_break, by});
    }
  }
  return out;
}

}  // namespace retarget
