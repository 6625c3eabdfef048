#include "core/log.h"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "core/error.h"

namespace retarget {
namespace {

// Captures log messages for one test and restores the previous sink and level after it.
struct Capture {
  std::vector<std::pair<log::Level, std::string>> lines;
  log::Sink previous;
  log::Level previous_level = log::level();

  Capture() {
    previous =
        log::set_sink([this](log::Level level, const std::string& message) { lines.emplace_back(level, message); });
  }
  ~Capture() {
    log::set_sink(previous);
    log::set_level(previous_level);
  }
};

}  // namespace

TEST_CASE("log formats its arguments and tags the level", "[log]") {
  Capture capture;
  log::set_level(log::Level::info);
  log::info("read {} vertices from {}", 5023, "a.obj");
  log::warn("{:.2f} of the faces are degenerate", 0.125);
  log::error("giving up");
  REQUIRE(capture.lines.size() == 3);
  CHECK(capture.lines[0] == std::make_pair(log::Level::info, std::string("read 5023 vertices from a.obj")));
  CHECK(capture.lines[1] == std::make_pair(log::Level::warn, std::string("0.12 of the faces are degenerate")));
  CHECK(capture.lines[2].first == log::Level::error);
}

TEST_CASE("messages below the level are dropped", "[log]") {
  Capture capture;
  log::set_level(log::Level::warn);
  CHECK_FALSE(log::enabled(log::Level::info));
  log::debug("d");
  log::info("i");
  log::warn("w");
  log::error("e");
  REQUIRE(capture.lines.size() == 2);
  CHECK(capture.lines[0].second == "w");
  CHECK(capture.lines[1].second == "e");

  log::set_level(log::Level::debug);
  log::debug("now {}", "visible");
  CHECK(capture.lines.back().second == "now visible");

  log::set_level(log::Level::off);
  log::error("silenced");
  log::write(log::Level::off, "never a message level");
  CHECK(capture.lines.size() == 3);
}

TEST_CASE("level names parse, and a bad one says what is accepted", "[log]") {
  for (auto level : {log::Level::debug, log::Level::info, log::Level::warn, log::Level::error, log::Level::off})
    CHECK(log::parse_level(log::level_name(level)) == level);
  CHECK(log::parse_level("warning") == log::Level::warn);
  CHECK_THROWS_AS(log::parse_level("loud"), Error);
  CHECK_THROWS_WITH(log::parse_level("loud"),
                    "log level: unknown level 'loud' (expected debug, info, warn, error or off)");
}

TEST_CASE("without a sink, lines go to stderr with a level tag", "[log]") {
  const log::Sink previous = log::set_sink(nullptr);
  const log::Level previous_level = log::level();
  log::set_level(log::Level::info);
  std::FILE* file = std::tmpfile();
  REQUIRE(file);
  std::fflush(stderr);
  const int saved = ::dup(STDERR_FILENO);
  ::dup2(::fileno(file), STDERR_FILENO);
  log::warn("disk {}% full", 93);
  log::debug("hidden");
  std::fflush(stderr);
  ::dup2(saved, STDERR_FILENO);
  ::close(saved);
  log::set_sink(previous);
  log::set_level(previous_level);

  std::rewind(file);
  char buffer[256] = {};
  const size_t n = std::fread(buffer, 1, sizeof buffer - 1, file);
  std::fclose(file);
  CHECK(std::string(buffer, n) == "[warn] disk 93% full\n");
}

TEST_CASE("set_sink returns the sink it replaces", "[log]") {
  Capture capture;
  int calls = 0;
  const log::Sink ours = log::set_sink([&](log::Level, const std::string&) { ++calls; });
  log::set_level(log::Level::info);
  log::info("to the counter");
  const log::Sink counter = log::set_sink(ours);
  REQUIRE(counter);
  log::info("to the capture");
  CHECK(calls == 1);
  REQUIRE(capture.lines.size() == 1);
  CHECK(capture.lines[0].second == "to the capture");
}

TEST_CASE("messages from several threads reach the sink whole, one at a time", "[log]") {
  Capture capture;  // its vector is not thread-safe: the log must serialise the calls
  log::set_level(log::Level::info);
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t)
    threads.emplace_back([t] {
      for (int i = 0; i < 500; ++i) log::info("thread {} message {}", t, i);
    });
  for (auto& thread : threads) thread.join();
  REQUIRE(capture.lines.size() == 4000);
  size_t whole = 0;
  for (const auto& line : capture.lines)
    whole += Catch::Matchers::Matches(R"(thread \d message \d+)").match(line.second);
  CHECK(whole == 4000);
}

}  // namespace retarget
