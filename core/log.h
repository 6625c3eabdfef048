// Logging for the library and the command-line tools: one line per message, a level tag,
// written to stderr (or to a sink installed by a test or an embedding application).
//
//   log::info("read {} vertices from {}", n, path);   // "[info] read 5023 vertices from a.obj"
#pragma once

#include <fmt/format.h>

#include <functional>
#include <string>
#include <utility>

namespace retarget::log {

enum class Level { debug, info, warn, error, off };

// Messages below `level` are dropped (default: info). `off` silences everything.
void set_level(Level level);
Level level();
inline bool enabled(Level message_level) { return message_level >= level() && message_level != Level::off; }

// "debug", "info", "warn", "error", "off".
const char* level_name(Level level);
// The inverse of level_name() ("warning" is taken for "warn"); throws retarget::Error
// listing the accepted names for anything else, e.g. a bad --log-level value.
Level parse_level(const std::string& name);

// Receives each message that passes the level filter: the level and the formatted text
// without tag or newline. Calls are serialised, so a sink need not be thread-safe.
using Sink = std::function<void(Level level, const std::string& message)>;
// Installs `sink` and returns the one it replaces; an empty sink restores stderr.
Sink set_sink(Sink sink);

// Writes one message (already formatted) if its level passes the filter.
void write(Level level, const std::string& message);

template <typename... Args>
void debug(fmt::format_string<Args...> format, Args&&... args) {
  if (enabled(Level::debug)) write(Level::debug, fmt::format(format, std::forward<Args>(args)...));
}
template <typename... Args>
void info(fmt::format_string<Args...> format, Args&&... args) {
  if (enabled(Level::info)) write(Level::info, fmt::format(format, std::forward<Args>(args)...));
}
template <typename... Args>
void warn(fmt::format_string<Args...> format, Args&&... args) {
  if (enabled(Level::warn)) write(Level::warn, fmt::format(format, std::forward<Args>(args)...));
}
template <typename... Args>
void error(fmt::format_string<Args...> format, Args&&... args) {
  if (enabled(Level::error)) write(Level::error, fmt::format(format, std::forward<Args>(args)...));
}

}  // namespace retarget::log
