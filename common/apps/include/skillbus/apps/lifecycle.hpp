// A server's life as a process: start-up errors end it with one line, SIGTERM and SIGINT
// end its run loop cleanly (so it still prints its summary).
#pragma once

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>

namespace skillbus::apps {

constexpr int kStartError = 2;  // the exit code of a server that cannot start

// The flag SIGTERM and SIGINT set once stop_on_signals() has been called: the servers'
// run loops end cleanly on it (and print their summary).
inline volatile std::sig_atomic_t& stop_requested() {
  static volatile std::sig_atomic_t flag = 0;
  return flag;
}
inline void stop_on_signals() {
  [[maybe_unused]] volatile std::sig_atomic_t& flag = stop_requested();  // created before any handler can run
  auto handler = [](int) { stop_requested() = 1; };
  std::signal(SIGTERM, handler);
  std::signal(SIGINT, handler);
}

// Runs a server's start-up; what it throws is printed as "<program>: cannot start: why"
// and ends the process with exit code kStartError.
template <class F>
void start_or_exit(const char* program, F&& start) {
  try {
    start();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: cannot start: %s\n", program, e.what());
    std::exit(kStartError);
  }
}

}  // namespace skillbus::apps
