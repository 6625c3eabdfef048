// AnnotationStore::open: the SQL schema, its creation in a new file and the upgrade of older ones.
#include <fmt/format.h>

#include <map>

#include "annotate/annotation_store.h"
#include "annotate/annotation_store_impl.h"
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

}  // namespace

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

}  // namespace retarget
