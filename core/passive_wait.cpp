#include "core/passive_wait.h"

#include <unistd.h>

#include <cstdlib>

namespace retarget {

void restart_with_passive_wait(char** argv) {
  if (std::getenv("OMP_WAIT_POLICY")) return;
  if (::setenv("OMP_WAIT_POLICY", "PASSIVE", 1) != 0) return;
  ::execv("/proc/self/exe", argv);
  // exec failed: go on as we are (the variable is set now, so a child we start inherits it).
}

}  // namespace retarget
