#include "annotate/sqlite.h"

#include <catch2/catch.hpp>
#include <string>

#include "annotate_test_support.h"
#include "core/error.h"

namespace retarget::sqlite {

using test::scratch_dir;

TEST_CASE("statements bind, step and read columns", "[sqlite]") {
  Database db = Database::open((scratch_dir("sqlite_basic") / "x.db").string());
  db.exec("CREATE TABLE t (i INTEGER, r REAL, s TEXT)", "create a table");
  Statement insert(db, "INSERT INTO t VALUES (?1, ?2, ?3)", "insert a row");
  Query(insert).bind(1, int64_t{1} << 40).bind(2, 0.5).bind(3, std::string("a,b")).run();
  Query(insert).bind(1, 2).bind(2, 1.5).bind_null(3).run();
  CHECK(db.last_insert_id() == 2);
  Statement select(db, "SELECT i, r, s FROM t ORDER BY i DESC", "read rows");
  Query q(select);
  REQUIRE(q.next());
  CHECK(q.int64(0) == int64_t{1} << 40);
  CHECK(q.real(1) == 0.5);
  CHECK(q.text(2) == "a,b");
  REQUIRE(q.next());
  CHECK(q.is_null(2));
  CHECK_FALSE(q.next());
}

TEST_CASE("a transaction rolls back unless committed", "[sqlite]") {
  Database db = Database::open((scratch_dir("sqlite_tx") / "x.db").string());
  db.exec("CREATE TABLE t (i INTEGER)", "create a table");
  {
    Transaction tx(db, Transaction::Kind::write, "insert");
    db.exec("INSERT INTO t VALUES (1)", "insert");
  }
  {
    Transaction tx(db, Transaction::Kind::write, "insert");
    db.exec("INSERT INTO t VALUES (2)", "insert");
    tx.commit();
  }
  Statement count(db, "SELECT sum(i) FROM t", "count");
  Query q(count);
  q.next();
  CHECK(q.int64(0) == 2);
}

TEST_CASE("sqlite errors name the file and what failed", "[sqlite]") {
  const auto dir = scratch_dir("sqlite_errors");
  Database db = Database::open((dir / "x.db").string());
  CHECK_THROWS_WITH(Statement(db, "SELECT x FROM nowhere", "read the nowhere table"),
                    Catch::Contains("x.db: cannot prepare the statement to read the nowhere table") &&
                        Catch::Contains("no such table: nowhere"));
  db.exec("CREATE TABLE t (i INTEGER NOT NULL UNIQUE)", "create a table");
  Statement insert(db, "INSERT INTO t VALUES (?1)", "add a number");
  Query(insert).bind(1, 1).run();
  CHECK_THROWS_WITH(Query(insert).bind(1, 1).run(),
                    Catch::Contains("x.db: cannot add a number") && Catch::Contains("SQLITE_CONSTRAINT"));
  CHECK_THROWS_WITH(Database::open((dir / "missing.db").string(), {30, false}),
                    Catch::Contains("missing.db: no such database file"));
  DatabaseOptions bad;
  bad.busy_timeout_seconds = 0;
  CHECK_THROWS_WITH(bad.validate(), Catch::Contains("database.busy_timeout_seconds: expected a positive number"));
}

}  // namespace retarget::sqlite
