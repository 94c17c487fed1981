// sb_rpc_counter: an RPC server of area COUNTER (tests and benchmarks of the RPC layer).
//
// Methods (payload rpc_counter_t both ways):
//   add    counter[key] += amount; writes[key] += 1; replies the new value and writes
//   get    replies counter[key] and writes[key]
//   fail   always answers an ERROR reply (to test typed errors)
// --drop-every N drops every N-th message it publishes (RPC tests under loss).
// --exit-after-idle-ms stops it after that long without a request (default: never).
// SIGTERM or SIGINT stop it; it then prints its statistics as JSON.
//
// Reads:   SB_COUNTER_REQ       Writes: SB_COUNTER_REP
#include <csignal>
#include <cstdio>
#include <map>

#include "args.hpp"
#include "skillbus/faulty_bus.hpp"
#include "skillbus/rpc.hpp"
#include "skillbus_msgs/rpc_counter_t.hpp"

using namespace skillbus;
using skillbus_msgs::rpc_counter_t;

namespace {
volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }
}  // namespace

int main(int argc, char** argv) {
  apps::Args args(argc, argv, {"url", "drop-every", "exit-after-idle-ms", "area"});
  std::unique_ptr<Bus> bus;
  try {
    bus = std::make_unique<DropEveryNthBus>(open_bus(args.str("url")), static_cast<int>(args.num("drop-every", 0)));
  } catch (const std::exception& e) {
    apps::Args::die(e.what());
  }
  std::map<std::string, rpc_counter_t> counters;
  RpcServer server(*bus, args.str("area", "COUNTER"));
  server.add_method<rpc_counter_t, rpc_counter_t>("add", [&](const rpc_counter_t& r) {
    rpc_counter_t& c = counters[r.key];
    c.key = r.key;
    c.value += r.amount;
    c.writes += 1;
    return c;
  });
  server.add_method<rpc_counter_t, rpc_counter_t>("get", [&](const rpc_counter_t& r) {
    auto it = counters.find(r.key);
    if (it == counters.end()) {
      rpc_counter_t none{};
      none.key = r.key;
      return none;
    }
    return it->second;
  });
  server.add_method<rpc_counter_t, rpc_counter_t>("fail", [](const rpc_counter_t& r) -> rpc_counter_t {
    throw std::runtime_error("asked to fail for key '" + r.key + "'");
  });
  std::fprintf(stderr, "sb_rpc_counter: serving %s on %s\n", rpc_request_channel(args.str("area", "COUNTER")).c_str(),
               bus->url().c_str());
  const long long idle_ms = args.num("exit-after-idle-ms", -1);
  auto last = std::chrono::steady_clock::now();
  std::signal(SIGTERM, on_signal);  // stop cleanly and print the statistics
  std::signal(SIGINT, on_signal);
  while (!g_stop) {
    if (bus->handle(std::chrono::milliseconds(100))) last = std::chrono::steady_clock::now();
    if (idle_ms >= 0 && std::chrono::steady_clock::now() - last > std::chrono::milliseconds(idle_ms)) break;
  }
  std::printf("{\"served\": %ld, \"duplicates\": %ld, \"expired\": %ld, \"bad_input\": %ld}\n", server.served(),
              server.duplicates(), server.expired(), server.bad_input().total());
  return 0;
}
