// One `retarget pipeline` at a time per run folder: two writing the same stages would each
// overwrite the other's files and manifests. The lock is the kernel's (flock on
// RUN/pipeline/lock), so a process that dies, even by SIGKILL, leaves no stale lock behind.
#pragma once

#include <string>

namespace retarget {

class RunLock {
 public:
  // Takes the lock of `run` (creating RUN/pipeline/), or throws retarget::Error naming the run
  // folder and the pid that holds it ("another `retarget pipeline` (pid 1234) is running on ...").
  explicit RunLock(const std::string& run);
  ~RunLock();
  RunLock(const RunLock&) = delete;
  RunLock& operator=(const RunLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace retarget
