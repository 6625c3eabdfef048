#include "core/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>

#include "core/error.h"
#include "core/log.h"

namespace retarget {

namespace fs = std::filesystem;

std::string temporary_path_for(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  const fs::path target(path);
  if (target.has_parent_path()) {
    std::error_code ec;
    fs::create_directories(target.parent_path(), ec);
    if (ec) throw Error(target.parent_path().string(), "cannot create folder: " + ec.message());
  }
  return path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
}

void discard_temporary_file(const std::string& temporary) noexcept {
  std::error_code ec;
  fs::remove(temporary, ec);
}

namespace {

// The writer's pid of a temporary's name "<name>.tmp.<pid>.<n>", or -1 if the name is not one.
long temporary_writer(const std::string& name) {
  const size_t at = name.rfind(".tmp.");
  if (at == std::string::npos || at == 0) return -1;
  const std::string rest = name.substr(at + 5);
  const size_t dot = rest.find('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == rest.size() || dot > 9) return -1;
  for (size_t i = 0; i < rest.size(); ++i)
    if (i != dot && (rest[i] < '0' || rest[i] > '9')) return -1;
  return std::stol(rest.substr(0, dot));
}

bool process_runs(long pid) { return pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM); }

}  // namespace

StaleTemporaries remove_stale_temporaries(const std::string& folder) noexcept {
  StaleTemporaries removed;
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const long pid = temporary_writer(it->path().filename().string());
    std::error_code entry_error;
    if (pid < 0 || process_runs(pid) || !it->is_regular_file(entry_error)) continue;
    const uintmax_t size = it->file_size(entry_error);
    const bool sized = !entry_error;
    if (fs::remove(it->path(), entry_error)) {
      ++removed.files;
      if (sized) removed.bytes += size;
    }
  }
  if (removed.files > 0) try {
      log::info("removed {} stale temporary file{} ({:.1f} MB) an interrupted write left in {}", removed.files,
                removed.files == 1 ? "" : "s", static_cast<double>(removed.bytes) / 1e6, folder);
    } catch (...) {  // a log line is not worth an exception out of a noexcept cleanup
    }
  return removed;
}

void commit_temporary_file(const std::string& temporary, const std::string& path) {
  const int fd = ::open(temporary.c_str(), O_RDONLY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    const std::string reason = std::strerror(errno);
    discard_temporary_file(temporary);
    throw Error(path, "cannot move the finished file into place: " + reason);
  }
}

namespace {

thread_local FlushGroup* current_group = nullptr;  // the innermost FlushGroup of this thread

// Flushes the file system each temporary is on, once per file system (syncfs); where that fails,
// each file on its own (fsync).
void flush_temporaries(const std::vector<std::pair<std::string, std::string>>& files) {
  std::set<dev_t> flushed;
  for (const auto& [temporary, path] : files) {
    const int fd = ::open(temporary.c_str(), O_RDONLY);
    if (fd < 0) continue;  // its rename then says what is wrong
    struct stat info {};
    const bool known = ::fstat(fd, &info) == 0;
    if (!known || !flushed.count(info.st_dev)) {
      if (::syncfs(fd) == 0 && known)
        flushed.insert(info.st_dev);
      else
        ::fsync(fd);
    }
    ::close(fd);
  }
}

}  // namespace

FlushGroup::FlushGroup() : outer_(current_group) { current_group = this; }

FlushGroup::~FlushGroup() {
  current_group = outer_;
  for (const auto& [temporary, path] : pending_) discard_temporary_file(temporary);
}

std::vector<std::pair<std::string, std::string>> FlushGroup::commit() {
  std::vector<std::pair<std::string, std::string>> files, failed;
  files.swap(pending_);
  flush_temporaries(files);
  for (const auto& [temporary, path] : files) {
    if (std::rename(temporary.c_str(), path.c_str()) == 0) continue;
    const std::string reason = std::strerror(errno);
    discard_temporary_file(temporary);
    failed.emplace_back(path, Error(path, "cannot move the finished file into place: " + reason).what());
  }
  return failed;
}

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  const std::string temporary = temporary_path_for(path);
  try {
    {
      std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
      if (!out) throw Error(path, std::string("cannot open for writing: ") + std::strerror(errno));
      write(out);
      out.flush();
      if (!out) throw Error(path, "write failed (disk full or file system error)");
    }
    if (FlushGroup* group = current_group) {
      group->pending_.emplace_back(temporary, path);
      return;
    }
    commit_temporary_file(temporary, path);
  } catch (...) {
    discard_temporary_file(temporary);
    throw;
  }
}

}  // namespace retarget
