#include "core/error.h"

#include <utility>

namespace retarget {

namespace {
std::string render(const std::string& where, const std::string& what) {
  return where.empty() ? what : where + ": " + what;
}
}  // namespace

Error::Error(std::string where, std::string what)
    : std::runtime_error(render(where, what)), where_(std::move(where)), detail_(std::move(what)) {}

Error::Error(std::string what) : Error(std::string(), std::move(what)) {}

}  // namespace retarget
