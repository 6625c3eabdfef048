#include "web/stop_signals.h"

#include <pthread.h>

#include <thread>

namespace retarget {

StopSignals::StopSignals() {
  sigemptyset(&signals_);
  sigaddset(&signals_, SIGINT);
  sigaddset(&signals_, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals_, nullptr);
}

void StopSignals::serve(const std::function<void()>& run, const std::function<void()>& stop) const {
  const sigset_t signals = signals_;
  std::thread stopper([&stop, signals] {
    int signal = 0;
    sigwait(&signals, &signal);
    stop();
  });
  // Stopped by a signal: the stopper has returned. Stopped otherwise (or failed): wake it.
  const auto wake = [&stopper] {
    pthread_kill(stopper.native_handle(), SIGTERM);
    stopper.join();
  };
  try {
    run();
  } catch (...) {
    wake();
    throw;
  }
  wake();
}

}  // namespace retarget
