// Serving until a signal: SIGINT (Ctrl-C) and SIGTERM stop a page's server (the annotation tool's,
// the landmark editor's) from a thread of their own, so the server's own loop needs no signal
// handler and stops as it would from any other thread.
#pragma once

#include <signal.h>

#include <functional>

namespace retarget {

class StopSignals {
 public:
  // Blocks SIGINT and SIGTERM in the calling thread. Make it before starting any thread (the
  // server's among them): every thread started later inherits the mask, so only serve()'s waiting
  // thread sees them.
  StopSignals();

  // Runs `run` (a server's blocking loop) until it returns; SIGINT or SIGTERM meanwhile calls
  // `stop` (from another thread), which must make `run` return.
  void serve(const std::function<void()>& run, const std::function<void()>& stop) const;

 private:
  sigset_t signals_;
};

}  // namespace retarget
