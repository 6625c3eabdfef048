#include "core/progress.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <utility>

namespace retarget {

namespace {

constexpr double kBarInterval = 0.1;    // seconds between redraws of the bar
constexpr double kPlainInterval = 5.0;  // longest silence in plain mode
constexpr int kBarWidth = 24;

bool is_terminal(const std::ostream* out) {
  int fd = -1;
  if (out == &std::cerr || out == &std::clog) fd = STDERR_FILENO;
  if (out == &std::cout) fd = STDOUT_FILENO;
  if (fd < 0 || !::isatty(fd)) return false;
  const char* term = std::getenv("TERM");
  return !(term && std::strcmp(term, "dumb") == 0);
}

}  // namespace

std::string format_duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  if (seconds < 0.9995) return fmt::format("{:.0f}ms", seconds * 1000);
  if (std::round(seconds * 10) < 600) return fmt::format("{:.1f}s", seconds);
  const int64_t s = std::llround(seconds);
  if (s < 3600) return fmt::format("{}m{:02}s", s / 60, s % 60);
  const int64_t m = (s + 30) / 60;
  return fmt::format("{}h{:02}m", m / 60, m % 60);
}

std::string format_rate(double per_second) {
  if (!std::isfinite(per_second) || per_second < 0) return "?/s";
  if (per_second >= 1e6) return fmt::format("{:.1f}M/s", per_second / 1e6);
  if (per_second >= 1e4) return fmt::format("{:.1f}k/s", per_second / 1e3);
  if (per_second >= 100) return fmt::format("{:.0f}/s", per_second);
  if (per_second >= 1) return fmt::format("{:.1f}/s", per_second);
  return fmt::format("{:.2f}/s", per_second);
}

Progress::Progress(std::string label, int64_t total, std::ostream* out, bool force_plain)
    : label_(std::move(label)),
      total_(std::max<int64_t>(total, 0)),
      out_(out),
      bar_(!force_plain && is_terminal(out)),
      exceptions_at_start_(std::uncaught_exceptions()) {
  if (bar_) {
    std::lock_guard<std::mutex> lock(mutex_);
    report(0, 0);
  } else {
    next_due_ = kPlainInterval;
  }
}

Progress::~Progress() {
  if (std::uncaught_exceptions() == exceptions_at_start_) {
    finish();
    return;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (bar_ && !finished_) *out_ << '\n' << std::flush;
}

bool Progress::due(int64_t done, double now) const {
  if (now >= next_due_.load(std::memory_order_relaxed)) return true;
  if (bar_ || total_ == 0 || done >= total_) return false;  // 100% is the final line's
  return done * 10 / total_ > reported_tenths_.load(std::memory_order_relaxed);
}

void Progress::advance(int64_t n) {
  const int64_t done = count_.fetch_add(n, std::memory_order_relaxed) + n;
  if (!out_) return;
  const double now = clock_.seconds();
  if (!due(done, now)) return;
  std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock() || finished_ || !due(done, now)) return;
  report(done, now);
}

std::string Progress::status(int64_t done, double now) const {
  const double rate = now > 0 ? done / now : 0;
  std::string text = total_ > 0 ? fmt::format("{}/{}", done, total_) : fmt::format("{}", done);
  if (total_ > 0) text += fmt::format(bar_ ? " {}%" : " ({}%)", std::min<int64_t>(done * 100 / total_, 100));
  if (done > 0) text += " " + format_rate(rate);
  if (total_ > 0 && done > 0 && done < total_) text += " eta " + format_duration((total_ - done) / rate);
  if (total_ == 0) text += " " + format_duration(now);
  return text;
}

void Progress::report(int64_t done, double now) {
  if (!out_) return;
  if (bar_) {
    std::string bar;
    if (total_ > 0) {
      const int filled = static_cast<int>(std::min<int64_t>(done * kBarWidth / total_, kBarWidth));
      bar = "[" + std::string(filled, '#') + std::string(kBarWidth - filled, '-') + "] ";
    }
    // "\033[K" clears what is left of a longer previous line.
    *out_ << '\r' << label_ << ' ' << bar << status(done, now) << "\033[K" << std::flush;
    next_due_.store(now + kBarInterval, std::memory_order_relaxed);
  } else {
    *out_ << label_ << ": " << status(done, now) << '\n' << std::flush;
    next_due_.store(now + kPlainInterval, std::memory_order_relaxed);
    if (total_ > 0) reported_tenths_.store(static_cast<int>(std::min<int64_t>(done * 10 / total_, 9)));
  }
}

void Progress::finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  finished_ = true;
  if (!out_) return;
  const double now = clock_.seconds();
  const int64_t done = count();
  const std::string count_text =
      total_ > 0 && done != total_ ? fmt::format("{}/{}", done, total_) : fmt::format("{}", done);
  const std::string line = fmt::format("{}: {} done in {} ({})", label_, count_text, format_duration(now),
                                       format_rate(now > 0 ? done / now : 0));
  if (bar_)
    *out_ << '\r' << line << "\033[K\n" << std::flush;
  else
    *out_ << line << '\n' << std::flush;
}

}  // namespace retarget
