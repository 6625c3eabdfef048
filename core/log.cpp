#include "core/log.h"

#include <atomic>
#include <cstdio>
#include <mutex>

#include "core/error.h"

namespace retarget::log {

namespace {

std::atomic<Level> current_level{Level::info};

// One mutex for the sink and the write, so lines from several threads never interleave.
std::mutex& sink_mutex() {
  static std::mutex mutex;
  return mutex;
}
Sink& current_sink() {
  static Sink sink;
  return sink;
}

}  // namespace

void set_level(Level level) { current_level.store(level, std::memory_order_relaxed); }

Level level() { return current_level.load(std::memory_order_relaxed); }

const char* level_name(Level level) {
  switch (level) {
    case Level::debug:
      return "debug";
    case Level::info:
      return "info";
    case Level::warn:
      return "warn";
    case Level::error:
      return "error";
    case Level::off:
      return "off";
  }
  return "?";
}

Level parse_level(const std::string& name) {
  for (Level level : {Level::debug, Level::info, Level::warn, Level::error, Level::off})
    if (name == level_name(level)) return level;
  if (name == "warning") return Level::warn;
  throw Error("log level", "unknown level '" + name + "' (expected debug, info, warn, error or off)");
}

Sink set_sink(Sink sink) {
  std::lock_guard<std::mutex> lock(sink_mutex());
  std::swap(current_sink(), sink);
  return sink;
}

void write(Level level, const std::string& message) {
  if (!enabled(level)) return;
  std::lock_guard<std::mutex> lock(sink_mutex());
  if (current_sink()) {
    current_sink()(level, message);
    return;
  }
  // One fwrite per line: stderr is unbuffered, so this keeps the line whole even against
  // writers that do not take our mutex.
  const std::string line = fmt::format("[{}] {}\n", level_name(level), message);
  std::fwrite(line.data(), 1, line.size(), stderr);
}

}  // namespace retarget::log
