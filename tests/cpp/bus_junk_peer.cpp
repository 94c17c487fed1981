// bus_junk_peer: the C++ half of tests/integration/test_junk_flood.py's queued-junk test.
//   bus_junk_peer FLAG  subscribes to SB_WANTED on the bus ($SKILLBUS_BUS_URL), prints
//                       "ready", waits (30 s at most) until the file FLAG exists (the
//                       Python half queues its datagrams meanwhile), then calls handle(0)
//                       until it returns false and prints {"got": N}: the SB_WANTED
//                       messages it read among the junk.
#include <sys/stat.h>

#include <chrono>
#include <cstdio>
#include <thread>

#include "skillbus/bus.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: bus_junk_peer FLAG\n");
    return 2;
  }
  auto bus = skillbus::open_bus();
  int got = 0;
  bus->subscribe("SB_WANTED", [&](const std::string&, const uint8_t*, size_t) { ++got; });
  std::printf("ready\n");
  std::fflush(stdout);
  struct stat st {};
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (::stat(argv[1], &st) != 0) {
    if (std::chrono::steady_clock::now() > end) {
      std::fprintf(stderr, "bus_junk_peer: no %s within 30 s\n", argv[1]);
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  while (bus->handle(std::chrono::milliseconds(0))) {
  }
  std::printf("{\"got\": %d}\n", got);
  return 0;
}
