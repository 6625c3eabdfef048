#include "core/error.h"

#include <c10/util/Exception.h>

#include <exception>
#include <new>
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

std::string describe_current_exception() {
  try {
    throw;
  } catch (const Error& e) {
    return e.what();
  } catch (const std::bad_alloc& e) {
    return std::string("out of memory (") + e.what() + "): a size in the input or the options is too large";
  } catch (const c10::Error& e) {
    return std::string("LibTorch error: ") + e.what_without_backtrace();
  } catch (const std::exception& e) {
    return std::string("unexpected error: ") + e.what();
  } catch (...) {
    return "unexpected error of an unknown kind";
  }
}

}  // namespace retarget
