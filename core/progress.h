// Progress of a long loop, for people watching a terminal and for log files alike.
//
//   Progress progress("sampling", n);
//   for (...) { ...; progress.advance(); }   // may be called from several threads
//   progress.finish();                       // "sampling: 2000 done in 16.6s (120.5/s)"
#pragma once

#include <atomic>
#include <cstdint>
#include <iostream>
#include <mutex>
#include <string>

#include "core/timer.h"

namespace retarget {

class Progress {
 public:
  // `total` items are expected (0 or less if unknown: no percentage or ETA). Output goes to
  // `out` (nullptr: none). When `out` is std::cerr/std::clog/std::cout and that stream is a
  // terminal, a bar with count, rate and ETA is redrawn in place at most 10 times a second;
  // otherwise (or with force_plain) a plain line is printed at each further 10% and at least
  // every 5 s, e.g. "label: 500/2000 (25%) 120.3/s eta 12s".
  Progress(std::string label, int64_t total, std::ostream* out = &std::cerr, bool force_plain = false);
  // Finishes if finish() was not called, unless an exception is unwinding (then it only ends
  // the bar's line, so the report does not claim the work was done).
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  // Counts n more items done. Thread-safe and cheap: reporting is throttled and a thread that
  // finds another one reporting does not wait for it.
  void advance(int64_t n = 1);
  // Prints the final line with total time and mean rate. Later calls do nothing.
  void finish();

  int64_t count() const { return count_.load(std::memory_order_relaxed); }
  // True if drawing an in-place bar rather than plain lines.
  bool interactive() const { return bar_; }

 private:
  bool due(int64_t done, double now) const;
  void report(int64_t done, double now);  // mutex_ held
  std::string status(int64_t done, double now) const;

  const std::string label_;
  const int64_t total_;
  std::ostream* const out_;
  const bool bar_;
  const int exceptions_at_start_;
  Stopwatch clock_;
  std::atomic<int64_t> count_{0};
  std::atomic<double> next_due_{0};  // seconds since start; the next report regardless of %
  std::atomic<int> reported_tenths_{0};
  std::mutex mutex_;
  bool finished_ = false;
};

// A duration for people: "850ms", "12.3s", "3m05s", "1h02m". "?" if negative or not finite.
std::string format_duration(double seconds);
// A rate: "0.25/s", "12.3/s", "120/s", "45.6k/s", "1.2M/s".
std::string format_rate(double per_second);

}  // namespace retarget
