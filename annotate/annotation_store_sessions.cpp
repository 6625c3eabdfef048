// The web tool's sign-in sessions in AnnotationStore: tokens standing for annotators, kept in the
// store so that they outlive the server process.
#include <fmt/format.h>

#include "annotate/annotation_store.h"
#include "annotate/annotation_store_impl.h"

namespace retarget {

using sqlite::Query;
using sqlite::Transaction;

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

}  // namespace retarget
