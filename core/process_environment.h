// Environments for child processes: this process's environment with some variables set, as
// "NAME=value" entries ready for execve (built before a fork, where a child may only call
// async-signal-safe functions).
#pragma once

#include <map>
#include <string>
#include <vector>

namespace retarget {

// This process's environment with each of `set` (name -> value) added, or replacing the entry of
// that name; the rest in their order, then `set` in name order.
std::vector<std::string> environment_with(const std::map<std::string, std::string>& set);

}  // namespace retarget
