#include "annotate/sqlite.h"

#include <fmt/format.h>
#include <sqlite3.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <thread>
#include <utility>

#include "core/config.h"
#include "core/error.h"

namespace retarget::sqlite {

namespace fs = std::filesystem;

namespace {

const char* code_name(int code) {
  switch (code & 0xff) {
    case SQLITE_BUSY:
      return "SQLITE_BUSY";
    case SQLITE_LOCKED:
      return "SQLITE_LOCKED";
    case SQLITE_CONSTRAINT:
      return "SQLITE_CONSTRAINT";
    case SQLITE_CORRUPT:
      return "SQLITE_CORRUPT";
    case SQLITE_NOTADB:
      return "SQLITE_NOTADB";
    case SQLITE_CANTOPEN:
      return "SQLITE_CANTOPEN";
    case SQLITE_READONLY:
      return "SQLITE_READONLY";
    case SQLITE_FULL:
      return "SQLITE_FULL";
    case SQLITE_IOERR:
      return "SQLITE_IOERR";
    case SQLITE_PERM:
      return "SQLITE_PERM";
    case SQLITE_MISUSE:
      return "SQLITE_MISUSE";
    case SQLITE_RANGE:
      return "SQLITE_RANGE";
    case SQLITE_ERROR:
      return "SQLITE_ERROR";
    default:
      return "SQLite error";
  }
}

// One mutex per database file and process, shared by every connection this process opens to it.
std::shared_ptr<std::mutex> writer_mutex_for(const std::string& path) {
  static std::mutex registry_mutex;
  static std::map<std::string, std::weak_ptr<std::mutex>> registry;
  std::error_code ec;
  fs::path key = fs::weakly_canonical(fs::absolute(path), ec);
  if (ec) key = fs::absolute(path);
  std::lock_guard<std::mutex> lock(registry_mutex);
  std::weak_ptr<std::mutex>& slot = registry[key.string()];
  std::shared_ptr<std::mutex> mutex = slot.lock();
  if (!mutex) {
    mutex = std::make_shared<std::mutex>();
    slot = mutex;
  }
  return mutex;
}

}  // namespace

void DatabaseOptions::validate(const std::string& key_path) const {
  require(std::isfinite(busy_timeout_seconds) && busy_timeout_seconds > 0, key_path + ".busy_timeout_seconds",
          fmt::format("expected a positive number of seconds, got {}", busy_timeout_seconds));
}

Database::Database(sqlite3* db, std::string path, std::shared_ptr<std::mutex> writer_mutex)
    : db_(db), path_(std::move(path)), writer_mutex_(std::move(writer_mutex)) {}

Database::Database(Database&& other) noexcept
    : db_(std::exchange(other.db_, nullptr)),
      path_(std::move(other.path_)),
      busy_timeout_seconds_(other.busy_timeout_seconds_),
      writer_mutex_(std::move(other.writer_mutex_)) {}

Database& Database::operator=(Database&& other) noexcept {
  if (this != &other) {
    if (db_) sqlite3_close_v2(db_);
    db_ = std::exchange(other.db_, nullptr);
    path_ = std::move(other.path_);
    busy_timeout_seconds_ = other.busy_timeout_seconds_;
    writer_mutex_ = std::move(other.writer_mutex_);
  }
  return *this;
}

Database::~Database() {
  if (db_) sqlite3_close_v2(db_);
}

Database Database::open(const std::string& path, const DatabaseOptions& options) {
  options.validate();
  if (path.empty()) throw Error("annotation store", "the database path is empty");
  if (options.create) {
    const fs::path parent = fs::path(path).parent_path();
    if (!parent.empty()) {
      std::error_code ec;
      fs::create_directories(parent, ec);
      if (ec) throw Error(parent.string(), "cannot create folder for the database: " + ec.message());
    }
  } else if (!fs::exists(path)) {
    throw Error(path, "no such database file");
  }
  sqlite3* handle = nullptr;
  const int flags = SQLITE_OPEN_READWRITE | (options.create ? SQLITE_OPEN_CREATE : 0);
  const int code = sqlite3_open_v2(path.c_str(), &handle, flags, nullptr);
  Database db(handle, path, writer_mutex_for(path));
  if (code != SQLITE_OK) {
    if (!handle) throw Error(path, "cannot open the database: out of memory");
    db.fail("open the database", code);
  }
  sqlite3_busy_timeout(handle, static_cast<int>(std::lround(options.busy_timeout_seconds * 1000)));
  db.busy_timeout_seconds_ = options.busy_timeout_seconds;
  // Reading the schema is the first access to the file: a file that is not a database fails here.
  db.exec("PRAGMA foreign_keys = ON; SELECT count(*) FROM sqlite_master;", "read the database header");
  return db;
}

void Database::enable_wal() {
  const auto start = std::chrono::steady_clock::now();
  while (true) {
    sqlite3_stmt* stmt = nullptr;
    int code = sqlite3_prepare_v2(db_, "PRAGMA journal_mode = WAL", -1, &stmt, nullptr);
    std::string mode;
    if (code == SQLITE_OK) {
      code = sqlite3_step(stmt);
      if (code == SQLITE_ROW) {
        const unsigned char* text = sqlite3_column_text(stmt, 0);
        mode = text ? reinterpret_cast<const char*>(text) : "";
        code = SQLITE_OK;
      }
    }
    sqlite3_finalize(stmt);
    if (code == SQLITE_OK) {
      if (mode != "wal") {
        throw Error(path_, fmt::format("cannot switch to WAL journaling (the journal mode stays '{}'; is the file on a "
                                       "network file system?)",
                                       mode));
      }
      return;
    }
    const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if ((code & 0xff) != SQLITE_BUSY || waited > busy_timeout_seconds_) fail("switch to WAL journaling", code);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

void Database::exec(const std::string& sql, const std::string& what) {
  char* message = nullptr;
  const int code = sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &message);
  if (code != SQLITE_OK) {
    const std::string text = message ? message : sqlite3_errstr(code);
    sqlite3_free(message);
    throw Error(path_, fmt::format("cannot {}: {} ({})", what, text, code_name(code)));
  }
}

void Database::fail(const std::string& what, int code) const {
  std::string text = db_ ? sqlite3_errmsg(db_) : sqlite3_errstr(code);
  if ((code & 0xff) == SQLITE_BUSY) text += "; another connection held the database longer than the busy timeout";
  throw Error(path_, fmt::format("cannot {}: {} ({})", what, text, code_name(code)));
}

int64_t Database::last_insert_id() const { return sqlite3_last_insert_rowid(db_); }

int Database::changes() const { return sqlite3_changes(db_); }

Statement::Statement(Database& db, const std::string& sql, std::string what) : db_(&db), what_(std::move(what)) {
  const int code = sqlite3_prepare_v3(db.handle(), sql.c_str(), static_cast<int>(sql.size() + 1),
                                      SQLITE_PREPARE_PERSISTENT, &stmt_, nullptr);
  if (code != SQLITE_OK) db.fail("prepare the statement to " + what_, code);
}

Statement::Statement(Statement&& other) noexcept
    : db_(other.db_), stmt_(std::exchange(other.stmt_, nullptr)), what_(std::move(other.what_)) {}

Statement& Statement::operator=(Statement&& other) noexcept {
  if (this != &other) {
    if (stmt_) sqlite3_finalize(stmt_);
    db_ = other.db_;
    stmt_ = std::exchange(other.stmt_, nullptr);
    what_ = std::move(other.what_);
  }
  return *this;
}

Statement::~Statement() {
  if (stmt_) sqlite3_finalize(stmt_);
}

Query::Query(Statement& statement) : statement_(statement) {
  sqlite3_reset(statement_.stmt_);
  sqlite3_clear_bindings(statement_.stmt_);
}

Query::~Query() { sqlite3_reset(statement_.stmt_); }

Query& Query::bind(int index, int64_t value) {
  const int code = sqlite3_bind_int64(statement_.stmt_, index, value);
  if (code != SQLITE_OK) statement_.db_->fail(fmt::format("bind parameter {} to {}", index, statement_.what_), code);
  return *this;
}

Query& Query::bind(int index, double value) {
  const int code = sqlite3_bind_double(statement_.stmt_, index, value);
  if (code != SQLITE_OK) statement_.db_->fail(fmt::format("bind parameter {} to {}", index, statement_.what_), code);
  return *this;
}

Query& Query::bind(int index, const std::string& value) {
  const int code =
      sqlite3_bind_text(statement_.stmt_, index, value.data(), static_cast<int>(value.size()), SQLITE_TRANSIENT);
  if (code != SQLITE_OK) statement_.db_->fail(fmt::format("bind parameter {} to {}", index, statement_.what_), code);
  return *this;
}

Query& Query::bind_null(int index) {
  const int code = sqlite3_bind_null(statement_.stmt_, index);
  if (code != SQLITE_OK) statement_.db_->fail(fmt::format("bind parameter {} to {}", index, statement_.what_), code);
  return *this;
}

bool Query::next() {
  const int code = sqlite3_step(statement_.stmt_);
  if (code == SQLITE_ROW) return true;
  if (code == SQLITE_DONE) return false;
  statement_.db_->fail(statement_.what_, code);
}

void Query::run() {
  while (next()) {
  }
}

bool Query::is_null(int column) const { return sqlite3_column_type(statement_.stmt_, column) == SQLITE_NULL; }

int64_t Query::int64(int column) const { return sqlite3_column_int64(statement_.stmt_, column); }

double Query::real(int column) const { return sqlite3_column_double(statement_.stmt_, column); }

std::string Query::text(int column) const {
  const unsigned char* text = sqlite3_column_text(statement_.stmt_, column);
  const int size = sqlite3_column_bytes(statement_.stmt_, column);
  return text ? std::string(reinterpret_cast<const char*>(text), static_cast<size_t>(size)) : std::string();
}

Transaction::Transaction(Database& db, Kind kind, const std::string& what) : db_(db), what_(what) {
  if (kind == Kind::write) writer_lock_ = std::unique_lock<std::mutex>(db.writer_mutex());
  db_.exec(kind == Kind::write ? "BEGIN IMMEDIATE" : "BEGIN", "begin a transaction to " + what_);
  open_ = true;
}

Transaction::~Transaction() {
  if (open_) sqlite3_exec(db_.handle(), "ROLLBACK", nullptr, nullptr, nullptr);
}

void Transaction::commit() {
  db_.exec("COMMIT", "commit the transaction to " + what_);
  open_ = false;
}

}  // namespace retarget::sqlite
