#include "core/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/error.h"

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
    commit_temporary_file(temporary, path);
  } catch (...) {
    discard_temporary_file(temporary);
    throw;
  }
}

}  // namespace retarget
