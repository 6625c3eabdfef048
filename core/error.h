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

// The message for an exception that is not a retarget::Error, as the executables print it when
// one reaches main(): what kind it is and its text, without LibTorch's backtrace, e.g.
//   "out of memory (std::bad_alloc): ..." or "LibTorch error: ...".
// Call it inside a catch block (it rethrows std::current_exception() to tell the kinds apart).
std::string describe_current_exception();

}  // namespace retarget
