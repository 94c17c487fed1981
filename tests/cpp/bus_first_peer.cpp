// bus_first_peer: the C++ reader of tests/integration/test_dds_late_joiner.py.
//   bus_first_peer CHANNEL  subscribes to CHANNEL on the bus ($SKILLBUS_BUS_URL) and prints
//                           {"subscribed_ns": W, "first": HEX}: the wall clock (ns) when it
//                           subscribed and the first 16 bytes of the first message it
//                           read (10 s at most; "" if none).
#include <chrono>
#include <cstdio>
#include <string>

#include "skillbus/bus.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: bus_first_peer CHANNEL\n");
    return 2;
  }
  auto bus = skillbus::open_bus();
  std::string first;
  bool got = false;
  const auto subscribed = std::chrono::system_clock::now();
  bus->subscribe(argv[1], [&](const std::string&, const uint8_t* d, size_t n) {
    if (got) return;
    got = true;
    char hex[3];
    for (size_t i = 0; i < n && i < 16; ++i) {
      std::snprintf(hex, sizeof hex, "%02x", d[i]);
      first += hex;
    }
  });
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!got && std::chrono::steady_clock::now() < end) bus->handle(std::chrono::milliseconds(50));
  const long long ns =
      std::chrono::duration_cast<std::chrono::nanoseconds>(subscribed.time_since_epoch()).count();
  std::printf("{\"subscribed_ns\": %lld, \"first\": \"%s\"}\n", ns, first.c_str());
  return got ? 0 : 1;
}
