#include "core/progress.h"

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "core/timer.h"

namespace retarget {
namespace {

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

size_t occurrences(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// Points stderr at a fresh pseudo-terminal while alive, so the terminal code path runs as it
// would for a user; read() collects what was drawn.
class PseudoTerminal {
 public:
  PseudoTerminal() {
    master_ = ::posix_openpt(O_RDWR | O_NOCTTY);
    if (master_ < 0 || ::grantpt(master_) != 0 || ::unlockpt(master_) != 0) return;
    const int slave = ::open(::ptsname(master_), O_RDWR | O_NOCTTY);
    if (slave < 0) return;
    std::cerr.flush();
    saved_ = ::dup(STDERR_FILENO);
    ::dup2(slave, STDERR_FILENO);
    ::close(slave);
    const char* term = std::getenv("TERM");
    saved_term_ = term ? term : "";
    ::setenv("TERM", "xterm", 1);
  }
  ~PseudoTerminal() {
    if (saved_ >= 0) {
      ::dup2(saved_, STDERR_FILENO);
      ::close(saved_);
      saved_term_.empty() ? ::unsetenv("TERM") : ::setenv("TERM", saved_term_.c_str(), 1);
    }
    if (master_ >= 0) ::close(master_);
  }
  bool ok() const { return saved_ >= 0; }

  // Everything written so far, waiting (up to 1 s) for `until` since a pty delivers lazily.
  std::string read(const std::string& until) {
    std::string text;
    Stopwatch waited;
    while (text.find(until) == std::string::npos && waited.seconds() < 1.0) {
      pollfd p{master_, POLLIN, 0};
      if (::poll(&p, 1, 50) <= 0) continue;
      char buffer[4096];
      const ssize_t n = ::read(master_, buffer, sizeof buffer);
      if (n <= 0) break;
      text.append(buffer, n);
    }
    return text;
  }

 private:
  int master_ = -1;
  int saved_ = -1;
  std::string saved_term_;
};

}  // namespace

TEST_CASE("durations and rates are formatted for people", "[progress]") {
  const std::pair<double, const char*> durations[] = {
      {0.0, "0ms"},      {0.25, "250ms"}, {0.9996, "1.0s"},  {12.34, "12.3s"}, {59.96, "1m00s"}, {185, "3m05s"},
      {3599.6, "1h00m"}, {3720, "1h02m"}, {90000, "25h00m"}, {-1, "?"},        {INFINITY, "?"},  {NAN, "?"},
  };
  for (const auto& [seconds, text] : durations) {
    INFO(seconds);
    CHECK(format_duration(seconds) == text);
  }
  const std::pair<double, const char*> rates[] = {
      {0.25, "0.25/s"}, {12.34, "12.3/s"}, {120.3, "120/s"}, {45600, "45.6k/s"}, {1.2e6, "1.2M/s"}, {NAN, "?/s"},
  };
  for (const auto& [rate, text] : rates) {
    INFO(rate);
    CHECK(format_rate(rate) == text);
  }
}

TEST_CASE("plain progress prints a line per 10% and a final summary", "[progress]") {
  std::ostringstream out;
  {
    Progress progress("load", 2000, &out);
    CHECK_FALSE(progress.interactive());
    for (int i = 0; i < 2000; ++i) progress.advance();
    CHECK(progress.count() == 2000);
    progress.finish();
    progress.finish();   // a second call adds nothing
    progress.advance();  // neither does advancing after the end
  }
  const auto lines = lines_of(out.str());
  REQUIRE(lines.size() == 10);
  for (int i = 0; i < 9; ++i) {
    INFO(lines[i]);
    const std::string head =
        "load: " + std::to_string(200 * (i + 1)) + "/2000 (" + std::to_string(10 * (i + 1)) + "%) ";
    CHECK_THAT(lines[i], Catch::Matchers::StartsWith(head) && Catch::Matchers::Matches(R"(.* [0-9.]+[kM]?/s eta \S+)"));
  }
  CHECK_THAT(lines[9], Catch::Matchers::Matches(R"(load: 2000 done in \S+ \([0-9.]+[kM]?/s\))"));
}

TEST_CASE("big steps report once per step, and a short count says how far it got", "[progress]") {
  std::ostringstream out;
  Progress progress("fit", 10, &out, /*force_plain=*/true);
  progress.advance(4);
  progress.finish();
  const auto lines = lines_of(out.str());
  REQUIRE(lines.size() == 2);
  CHECK_THAT(lines[0], Catch::Matchers::StartsWith("fit: 4/10 (40%) "));
  CHECK_THAT(lines[1], Catch::Matchers::StartsWith("fit: 4/10 done in "));
}

TEST_CASE("an unknown total counts without percentages", "[progress]") {
  std::ostringstream out;
  Progress progress("scan", 0, &out);
  progress.advance(3);
  progress.advance(2);
  progress.finish();
  const auto lines = lines_of(out.str());
  REQUIRE(lines.size() == 1);  // no 10% steps, and far less than the 5 s heartbeat
  CHECK_THAT(lines[0], Catch::Matchers::StartsWith("scan: 5 done in "));
}

TEST_CASE("the destructor finishes, except while an exception unwinds", "[progress]") {
  std::ostringstream normal;
  { Progress("quiet", 5, &normal).advance(5); }
  CHECK_THAT(normal.str(), Catch::Matchers::StartsWith("quiet: 5 done in "));

  std::ostringstream failed;
  try {
    Progress progress("doomed", 100, &failed);
    throw std::runtime_error("boom");
  } catch (const std::runtime_error&) {
  }
  CHECK(failed.str().empty());
}

TEST_CASE("advance is safe from several threads", "[progress]") {
  std::ostringstream out;
  Progress progress("par", 100000, &out);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&] {
      for (int i = 0; i < 25000; ++i) progress.advance();
    });
  for (auto& thread : threads) thread.join();
  CHECK(progress.count() == 100000);
  progress.finish();
  const auto lines = lines_of(out.str());
  REQUIRE(lines.size() >= 2);  // a thread that finds another one reporting skips a step
  REQUIRE(lines.size() <= 10);
  for (size_t i = 0; i + 1 < lines.size(); ++i)
    CHECK_THAT(lines[i], Catch::Matchers::Matches(R"(par: \d+/100000 \(\d+%\) .*)"));
  CHECK_THAT(lines.back(), Catch::Matchers::StartsWith("par: 100000 done in "));
}

TEST_CASE("no stream means no output but still a count", "[progress]") {
  Progress progress("silent", 3, nullptr);
  progress.advance(3);
  progress.finish();
  CHECK(progress.count() == 3);
  CHECK_FALSE(progress.interactive());
}

TEST_CASE("on a terminal a bar is redrawn in place, at most 10 times a second", "[progress]") {
  PseudoTerminal terminal;
  REQUIRE(terminal.ok());
  {
    Progress progress("bake", 1000, &std::cerr);
    CHECK(progress.interactive());
    for (int i = 0; i < 1000; ++i) progress.advance();
    progress.finish();
  }
  const std::string text = terminal.read("done in");
  INFO(text);
  CHECK(text.find("\rbake [------------------------] 0/1000 0%") != std::string::npos);
  // The loop takes far less than 0.1 s: the first draw and perhaps one more, not 1000.
  CHECK(occurrences(text, "\rbake [") >= 1);
  CHECK(occurrences(text, "\rbake [") <= 2);
  CHECK(text.find("\rbake: 1000 done in ") != std::string::npos);
  CHECK(text.find("\033[K") != std::string::npos);

  // force_plain keeps log-style lines even on a terminal.
  CHECK_FALSE(Progress("plain", 1, &std::cerr, /*force_plain=*/true).interactive());
}

TEST_CASE("a bar interrupted by an exception still ends its line", "[progress]") {
  PseudoTerminal terminal;
  REQUIRE(terminal.ok());
  try {
    Progress progress("cut", 10, &std::cerr);
    progress.advance(3);
    throw std::runtime_error("boom");
  } catch (const std::runtime_error&) {
  }
  const std::string text = terminal.read("\n");
  CHECK(text.find("\rcut [") != std::string::npos);
  CHECK(text.find("done in") == std::string::npos);
  CHECK(text.find('\n') != std::string::npos);
}

TEST_CASE("Stopwatch measures steady time and restarts", "[timer]") {
  Stopwatch watch;
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  const double ms = watch.milliseconds();
  CHECK(ms >= 20);
  CHECK(watch.seconds() >= ms / 1000);
  const double lap = watch.restart();
  CHECK(lap >= 0.02);
  CHECK(watch.seconds() < lap);
}

}  // namespace retarget
