#include "pipeline/run_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.h"

namespace fs = std::filesystem;

namespace retarget {

RunLock::RunLock(const std::string& run) {
  const fs::path folder = fs::path(run) / "pipeline";
  std::error_code ec;
  fs::create_directories(folder, ec);
  const std::string path = (folder / "lock").string();
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) throw Error(path, std::string("cannot open the run's lock: ") + std::strerror(errno));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    std::string holder;
    std::getline(std::ifstream(path), holder);
    ::close(fd_);
    fd_ = -1;
    if (error != EWOULDBLOCK) throw Error(path, std::string("cannot lock the run: ") + std::strerror(error));
    throw Error(run, "another `retarget pipeline`" + (holder.empty() ? std::string() : " (pid " + holder + ")") +
                         " is running on this run folder; wait for it to finish or stop it first");
  }
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, pid.data(), pid.size(), 0) != static_cast<ssize_t>(pid.size())) {
    // The pid is only for the message another run gives; the lock itself holds.
  }
}

RunLock::~RunLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the flock
}

}  // namespace retarget
