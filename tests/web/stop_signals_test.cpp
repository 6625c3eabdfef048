#include "web/stop_signals.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <stdexcept>
#include <thread>

using namespace retarget;

namespace {

// A stand-in for a server's loop: runs until stop() or until it gives up after 10 s.
struct Loop {
  std::atomic<bool> stopped{false};
  bool run() {
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (!stopped && std::chrono::steady_clock::now() < give_up)
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    return stopped;
  }
};

}  // namespace

TEST_CASE("StopSignals: SIGTERM sent to the process stops the loop through stop()", "[web]") {
  const StopSignals signals;
  Loop loop;
  bool stopped_by_signal = false;
  std::thread sender([] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    kill(getpid(), SIGTERM);  // blocked everywhere but in serve()'s waiting thread
  });
  signals.serve([&] { stopped_by_signal = loop.run(); }, [&] { loop.stopped = true; });
  sender.join();
  CHECK(stopped_by_signal);
}

TEST_CASE("StopSignals: a loop that ends by itself returns without a signal, twice", "[web]") {
  const StopSignals signals;
  int calls = 0;
  for (int i = 0; i < 2; ++i) signals.serve([&] { ++calls; }, [] {});
  CHECK(calls == 2);
}

TEST_CASE("StopSignals: an exception from the loop passes through", "[web]") {
  const StopSignals signals;
  CHECK_THROWS_AS(signals.serve([] { throw std::runtime_error("no port"); }, [] {}), std::runtime_error);
}
