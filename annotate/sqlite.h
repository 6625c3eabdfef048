// Small RAII wrappers over the sqlite3 C API: a connection, prepared statements, one execution
// of a statement, and transactions. Every failure throws retarget::Error whose `where` is the
// database file and whose message says what was being done and what SQLite answered
// ("annotations.db: cannot decide comparison: database is locked (SQLITE_BUSY)").
//
// A Database is one connection: use it from one thread at a time (give each thread its own).
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

struct sqlite3;
struct sqlite3_stmt;

namespace retarget::sqlite {

struct DatabaseOptions {
  double busy_timeout_seconds = 30;  // how long a statement waits for another connection's lock; > 0
  bool create = true;                // create the file (and missing parent folders) when absent

  // Throws retarget::Error naming `key_path`.<field> for a value out of range.
  void validate(const std::string& key_path = "database") const;
};

class Database {
 public:
  // Opens (or creates) `path`, turns on foreign keys, sets the busy timeout and checks that
  // the file is an SQLite database. Throws retarget::Error naming the path.
  static Database open(const std::string& path, const DatabaseOptions& options = {});

  Database(Database&& other) noexcept;
  Database& operator=(Database&& other) noexcept;
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;
  ~Database();

  // Runs one or more SQL statements without results; `what` describes them for errors
  // ("create the schema").
  void exec(const std::string& sql, const std::string& what);

  // Switches the file to WAL journaling (readers see a snapshot while one writer commits). The
  // switch needs the file to itself, and SQLite does not wait for that, so this retries until
  // the busy timeout: several processes may open a new file at once. Throws retarget::Error if
  // the file system does not support WAL.
  void enable_wal();

  // Throws retarget::Error(path(), "cannot <what>: <sqlite message> (<code name>)").
  [[noreturn]] void fail(const std::string& what, int code) const;

  const std::string& path() const { return path_; }
  sqlite3* handle() const { return db_; }
  // Serialises this process's writers to the same file (see Transaction): waiting on a mutex
  // is fairer and cheaper than SQLite's sleeping busy handler when many threads write.
  std::mutex& writer_mutex() const { return *writer_mutex_; }
  // The rowid of the last INSERT on this connection.
  int64_t last_insert_id() const;
  // Rows changed by the last INSERT, UPDATE or DELETE on this connection.
  int changes() const;

 private:
  Database(sqlite3* db, std::string path, std::shared_ptr<std::mutex> writer_mutex);

  sqlite3* db_ = nullptr;
  std::string path_;
  double busy_timeout_seconds_ = 0;
  std::shared_ptr<std::mutex> writer_mutex_;
};

// A statement prepared once and executed many times through Query.
class Statement {
 public:
  // `what` describes the statement for errors ("find the next open comparison").
  Statement(Database& db, const std::string& sql, std::string what);
  Statement(Statement&& other) noexcept;
  Statement& operator=(Statement&& other) noexcept;
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  ~Statement();

  const std::string& what() const { return what_; }

 private:
  friend class Query;
  Database* db_ = nullptr;
  sqlite3_stmt* stmt_ = nullptr;
  std::string what_;
};

// One execution of a Statement: bind parameters (1-based), step through rows, read columns
// (0-based). The statement is reset when the Query goes out of scope, so no read snapshot
// outlives it.
class Query {
 public:
  explicit Query(Statement& statement);
  Query(const Query&) = delete;
  Query& operator=(const Query&) = delete;
  ~Query();

  Query& bind(int index, int64_t value);
  Query& bind(int index, int value) { return bind(index, static_cast<int64_t>(value)); }
  Query& bind(int index, double value);
  Query& bind(int index, const std::string& value);
  Query& bind_null(int index);

  // Steps once: true if a row is available, false when the statement is done.
  bool next();
  // Steps a statement that returns no rows.
  void run();

  bool is_null(int column) const;
  int64_t int64(int column) const;
  int integer(int column) const { return static_cast<int>(int64(column)); }
  double real(int column) const;
  std::string text(int column) const;

 private:
  Statement& statement_;
};

// BEGIN (deferred, for a consistent read snapshot) or BEGIN IMMEDIATE (takes the write lock at
// once, so two writers never deadlock upgrading their locks). Rolls back in the destructor unless
// commit() was called. An immediate transaction also holds the connection's writer mutex.
class Transaction {
 public:
  enum class Kind { read, write };
  Transaction(Database& db, Kind kind, const std::string& what);
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  ~Transaction();

  void commit();

 private:
  Database& db_;
  std::unique_lock<std::mutex> writer_lock_;
  std::string what_;
  bool open_ = false;
};

}  // namespace retarget::sqlite
