// bus_late_reader_peer: the C++ reader of tests/integration/test_dds_late_joiner.py.
//   bus_late_reader_peer CHANNEL  subscribes to CHANNEL on the bus ($SKILLBUS_BUS_URL),
//                                 reads for 0.5 s from its first message (10 s at most for
//                                 that), and prints {"subscribed_ns": W, "earliest_ns": E,
//                                 "read": N}: the wall clock (ns) when it subscribed, and the
//                                 earliest of the writer's times (bytes 8-15 of each message,
//                                 big-endian ns) among the N messages it read.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <limits>
#include <string>

#include "skillbus/bus.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: bus_late_reader_peer CHANNEL\n");
    return 2;
  }
  auto bus = skillbus::open_bus();
  long long earliest = std::numeric_limits<long long>::max();
  int read = 0;
  const auto subscribed = std::chrono::system_clock::now();
  bus->subscribe(argv[1], [&](const std::string&, const uint8_t* d, size_t n) {
    if (n < 16) return;
    unsigned long long t = 0;
    for (int i = 8; i < 16; ++i) t = (t << 8) | d[i];
    earliest = std::min(earliest, static_cast<long long>(t));
    ++read;
  });
  using steady = std::chrono::steady_clock;
  const auto give_up = steady::now() + std::chrono::seconds(10);
  while (read == 0 && steady::now() < give_up) bus->handle(std::chrono::milliseconds(50));
  const auto end = steady::now() + std::chrono::milliseconds(500);
  while (read > 0 && steady::now() < end) bus->handle(std::chrono::milliseconds(20));
  const long long ns = std::chrono::duration_cast<std::chrono::nanoseconds>(subscribed.time_since_epoch()).count();
  std::printf("{\"subscribed_ns\": %lld, \"earliest_ns\": %lld, \"read\": %d}\n", ns, read ? earliest : 0, read);
  return read ? 0 : 1;
}
