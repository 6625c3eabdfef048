#include "core/atomic_file.h"

#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

#include "core/error.h"
#include "scratch.h"

namespace retarget {
namespace {

namespace fs = std::filesystem;

using test::scratch_dir;

std::string read_all(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

size_t entries(const fs::path& dir) {
  return static_cast<size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

}  // namespace

TEST_CASE("a write replaces the file and leaves nothing else behind", "[atomic_file]") {
  const fs::path dir = scratch_dir("atomic_replace");
  const std::string path = (dir / "out.txt").string();
  write_file_atomically(path, [](std::ostream& out) { out << "old contents, longer than the new"; });
  write_file_atomically(path, [](std::ostream& out) { out << "new"; });
  CHECK(read_all(path) == "new");
  CHECK(entries(dir) == 1);
}

TEST_CASE("a throwing writer leaves the old file intact and no temporary", "[atomic_file]") {
  const fs::path dir = scratch_dir("atomic_throw");
  const std::string path = (dir / "out.txt").string();
  write_file_atomically(path, [](std::ostream& out) { out << "old"; });
  CHECK_THROWS_WITH(write_file_atomically(path,
                                          [](std::ostream& out) {
                                            out << "half of the new";
                                            throw std::runtime_error("writer failed");
                                          }),
                    "writer failed");
  CHECK(read_all(path) == "old");
  CHECK(entries(dir) == 1);

  // Without an old file, nothing at all is left.
  const std::string fresh = (dir / "fresh.txt").string();
  CHECK_THROWS(write_file_atomically(fresh, [](std::ostream&) { throw std::runtime_error("no"); }));
  CHECK_FALSE(fs::exists(fresh));
  CHECK(entries(dir) == 1);
}

TEST_CASE("missing parent folders are created", "[atomic_file]") {
  const fs::path dir = scratch_dir("atomic_parents");
  const fs::path path = dir / "a" / "b" / "out.txt";
  write_file_atomically(path.string(), [](std::ostream& out) { out << "deep"; });
  CHECK(read_all(path) == "deep");
}

TEST_CASE("atomic file errors name the path", "[atomic_file]") {
  const fs::path dir = scratch_dir("atomic_errors");
  const fs::path blocker = dir / "file";
  std::ofstream(blocker) << "a file where a folder is wanted";
  const auto write = [](std::ostream& out) { out << "x"; };

  // The parent cannot be created: a file stands in its way.
  CHECK_THROWS_WITH(write_file_atomically((blocker / "sub" / "out.txt").string(), write),
                    Catch::Matchers::StartsWith((blocker / "sub").string() + ": cannot create folder: "));

  // The target is a non-empty folder, so the finished file cannot be moved over it.
  const fs::path folder = dir / "folder";
  fs::create_directories(folder / "inside");
  CHECK_THROWS_WITH(write_file_atomically(folder.string(), write),
                    Catch::Matchers::StartsWith(folder.string() + ": cannot move the finished file into place: "));

  // A name longer than the file system allows cannot be opened.
  const std::string too_long = (dir / std::string(300, 'n')).string();
  CHECK_THROWS_WITH(write_file_atomically(too_long, write),
                    Catch::Matchers::StartsWith(too_long + ": cannot open for writing: "));

  // Every failure cleaned up after itself.
  CHECK(entries(dir) == 2);
}

TEST_CASE("temporary paths are unique siblings that commit into place or are discarded", "[atomic_file]") {
  const fs::path dir = scratch_dir("atomic_temporary");
  const std::string path = (dir / "sub" / "model.pt").string();
  const std::string a = temporary_path_for(path), b = temporary_path_for(path);
  CHECK(a != b);
  CHECK(fs::path(a).parent_path() == fs::path(path).parent_path());
  CHECK(fs::is_directory(dir / "sub"));  // created for the writer

  std::ofstream(a) << "payload";
  commit_temporary_file(a, path);
  CHECK(read_all(path) == "payload");
  CHECK_FALSE(fs::exists(a));

  std::ofstream(b) << "abandoned";
  discard_temporary_file(b);
  CHECK_FALSE(fs::exists(b));
  CHECK(entries(dir / "sub") == 1);

  // A failed commit removes the temporary too.
  const std::string c = temporary_path_for(path);
  std::ofstream(c) << "x";
  fs::create_directories(dir / "taken" / "inside");
  CHECK_THROWS_WITH(
      commit_temporary_file(c, (dir / "taken").string()),
      Catch::Matchers::StartsWith((dir / "taken").string() + ": cannot move the finished file into place: "));
  CHECK_FALSE(fs::exists(c));
}

}  // namespace retarget

namespace retarget {
namespace {

// A pid that ran and has ended: a child that exits at once, reaped.
long ended_pid() {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  REQUIRE(child > 0);
  int status = 0;
  ::waitpid(child, &status, 0);
  return child;
}

TEST_CASE("stale temporaries of ended writers are removed, live writers' kept", "[atomic_file]") {
  const fs::path dir = scratch_dir("atomic_stale");
  const long dead = ended_pid();
  const std::string stale = "last.pt.tmp." + std::to_string(dead) + ".3";
  const std::string live = "last.pt.tmp." + std::to_string(::getpid()) + ".0";
  for (const std::string& name : {stale, live, std::string("last.pt"), std::string("notes.tmp.txt"),
                                  std::string("a.tmp.12x.1"), std::string("features.pt.tmp." + std::to_string(dead))})
    std::ofstream(dir / name) << "0123456789";
  const StaleTemporaries removed = remove_stale_temporaries(dir.string());
  CHECK(removed.files == 1);
  CHECK(removed.bytes == 10);
  CHECK_FALSE(fs::exists(dir / stale));
  for (const std::string& kept :
       {live, std::string("last.pt"), std::string("notes.tmp.txt"), std::string("a.tmp.12x.1")})
    CHECK(fs::exists(dir / kept));
  CHECK(remove_stale_temporaries((dir / "no such folder").string()).files == 0);
}

}  // namespace

TEST_CASE("a flush group writes its files in place only at commit, one flush for all", "[atomic_file]") {
  const fs::path dir = scratch_dir("atomic_group");
  auto text = [](const char* t) { return [t](std::ostream& out) { out << t; }; };
  write_file_atomically((dir / "a.txt").string(), text("old a"));
  {
    FlushGroup group;
    write_file_atomically((dir / "a.txt").string(), text("new a"));
    write_file_atomically((dir / "b.txt").string(), text("b"));
    // Until commit: the old file, no new one, the temporaries beside them.
    CHECK(read_all(dir / "a.txt") == "old a");
    CHECK_FALSE(fs::exists(dir / "b.txt"));
    CHECK(entries(dir) == 3);
    CHECK(group.commit().empty());
    CHECK(read_all(dir / "a.txt") == "new a");
    CHECK(read_all(dir / "b.txt") == "b");
    CHECK(entries(dir) == 2);
    // A file that cannot be moved into place (a folder holding a file is in the way) is named;
    // the others of the group are in place.
    fs::create_directories(dir / "c.txt");
    std::ofstream(dir / "c.txt" / "keep") << "x";
    write_file_atomically((dir / "c.txt").string(), text("c"));
    write_file_atomically((dir / "d.txt").string(), text("d"));
    const auto failed = group.commit();
    REQUIRE(failed.size() == 1);
    CHECK(failed[0].first == (dir / "c.txt").string());
    CHECK_THAT(failed[0].second,
               Catch::Contains("c.txt") && Catch::Contains("cannot move the finished file into place"));
    CHECK(read_all(dir / "d.txt") == "d");
    CHECK(entries(dir) == 4);  // a, b, c.txt/, d
    // Written and never committed: removed with the group.
    write_file_atomically((dir / "e.txt").string(), text("e"));
  }
  CHECK_FALSE(fs::exists(dir / "e.txt"));
  CHECK(entries(dir) == 4);
  // Without a group, each write is in place at once again.
  write_file_atomically((dir / "f.txt").string(), text("f"));
  CHECK(read_all(dir / "f.txt") == "f");
}

}  // namespace retarget
