#include "core/process_environment.h"

#include <unistd.h>

namespace retarget {

std::vector<std::string> environment_with(const std::map<std::string, std::string>& set) {
  std::vector<std::string> entries;
  for (char** e = environ; *e; ++e) {
    const std::string entry = *e;
    if (!set.count(entry.substr(0, entry.find('=')))) entries.push_back(entry);
  }
  for (const auto& [name, value] : set) entries.push_back(name + "=" + value);
  return entries;
}

}  // namespace retarget
