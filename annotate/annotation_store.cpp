#include "annotate/annotation_store.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>

#include "annotate/annotation_store_impl.h"
#include "core/config.h"
#include "core/error.h"

namespace retarget {

using sqlite::Query;
using sqlite::Transaction;
using store_internal::ComparisonRow;
using store_internal::GroupFacts;
using store_internal::parse_state;

namespace store_internal {

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

}  // namespace store_internal

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

std::optional<int64_t> AnnotationStore::Impl::annotator_id(const std::string& name) {
  Query q(find_annotator);
  q.bind(1, name);
  if (!q.next()) return std::nullopt;
  return q.int64(0);
}

int64_t AnnotationStore::Impl::require_annotator(const std::string& name) {
  std::optional<int64_t> id = annotator_id(name);
  if (!id) fail(fmt::format("unknown annotator '{}': it has never asked for a comparison", name));
  Query(touch_annotator).bind(1, *id).bind(2, now()).run();
  return *id;
}

int64_t AnnotationStore::Impl::upsert(const std::string& name) {
  if (name.empty()) fail("the annotator name is empty");
  Query(upsert_annotator).bind(1, name).bind(2, now()).run();
  return *annotator_id(name);
}

std::string AnnotationStore::Impl::name_of(std::optional<int64_t> id) {
  if (!id) return std::string();
  Query q(annotator_name);
  q.bind(1, *id);
  return q.next() ? q.text(0) : fmt::format("#{}", *id);
}

const GroupFacts& AnnotationStore::Impl::group_facts(int64_t group) {
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

std::optional<ComparisonRow> AnnotationStore::Impl::read_comparison(int64_t id) {
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

AnnotationStore::AnnotationStore(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
AnnotationStore::AnnotationStore(AnnotationStore&&) noexcept = default;
AnnotationStore& AnnotationStore::operator=(AnnotationStore&&) noexcept = default;
AnnotationStore::~AnnotationStore() = default;

const std::string& AnnotationStore::path() const { return impl_->db.path(); }

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

bool AnnotationStore::has_comparison(int64_t id) const { return impl_->read_comparison(id).has_value(); }

bool AnnotationStore::has_sample(int64_t sample) const {
  Query q(impl_->find_sample);
  q.bind(1, sample);
  return q.next();
}

}  // namespace retarget
