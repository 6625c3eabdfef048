// Errors a user can act on: every message says what is wrong and where
// (a file, a line, a YAML key path, a vertex index).
#pragma once

#include <stdexcept>
#include <string>

namespace retarget {

// Bad user input. `where` names the place (a file, "file:line", a key path,
// "vertex 17 of a.obj"); `what` says what is wrong there. what() renders
// "where: what" so a message can be printed as it is.
class Error : public std::runtime_error {
 public:
  Error(std::string where, std::string what);
  explicit Error(std::string what);

  const std::string& where() const { return where_; }
  const std::string& detail() const { return detail_; }

 private:
  std::string where_;
  std::string detail_;
};

}  // namespace retarget
