#include "core/option_errors.h"

#include <cmath>
#include <cstdlib>
#include <string_view>

namespace retarget {

namespace {

// True when `text` reads whole as a number (strtod's spelling).
bool reads_as_number(const std::string& text) {
  if (text.empty()) return false;
  char* end = nullptr;
  std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size();
}

// True when the message quotes `value` as cxxopts does ('V' or the typographic quotes).
bool quotes(const std::string& message, const std::string& value) {
  return message.find("'" + value + "'") != std::string::npos ||
         message.find("\xE2\x80\x98" + value + "\xE2\x80\x99") != std::string::npos;
}

}  // namespace

std::string explain_option_error(const std::string& message, int argc, char** argv) {
  if (message.rfind("Argument ", 0) != 0 || message.find("failed to parse") == std::string::npos) return message;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.size() < 2 || arg[0] != '-') continue;
    std::string name = arg, value;
    const size_t equals = arg.find('=');
    if (arg.rfind("--", 0) == 0 && equals != std::string::npos) {
      name = arg.substr(0, equals);
      value = arg.substr(equals + 1);
    } else if (i + 1 < argc) {
      value = argv[i + 1];
    } else {
      continue;
    }
    if (!quotes(message, value)) continue;
    const bool number = reads_as_number(value) && std::isfinite(std::strtod(value.c_str(), nullptr));
    return name + ": expected " + (number ? "a whole number in the option's range" : "a number") + ", got '" + value +
           "'";
  }
  return message;
}

}  // namespace retarget
