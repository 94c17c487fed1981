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
#include <cstdio>
#include <map>

#include "skillbus/apps/cli.hpp"
#include "skillbus/apps/lifecycle.hpp"
#include "skillbus/apps/summary.hpp"
#include "skillbus/faulty_bus.hpp"
#include "skillbus/rpc.hpp"
#include "skillbus_msgs/rpc_counter_t.hpp"

using namespace skillbus;
using skillbus_msgs::rpc_counter_t;

int main(int argc, char** argv) {
  CLI::App app{"An RPC server of area COUNTER (methods add, get, fail) for tests and benchmarks of the RPC layer; "
               "SIGTERM or SIGINT stop it and it prints its statistics as JSON.",
               "sb_rpc_counter"};
  apps::configure(app);
  std::string url, area = "COUNTER";
  int drop_every = 0;
  int64_t idle_ms = -1;
  apps::add_url_option(app, url);
  app.add_option("--area", area, "the RPC area it serves");
  app.add_option("--drop-every", drop_every, "tests: lose every N-th message it publishes (0: none)");
  app.add_option("--exit-after-idle-ms", idle_ms, "stop after this long without a request (-1: never)");
  apps::parse_or_exit(app, argc, argv);
  std::unique_ptr<Bus> bus;
  apps::start_or_exit("sb_rpc_counter",
                      [&] { bus = std::make_unique<DropEveryNthBus>(open_bus(url), drop_every); });
  std::map<std::string, rpc_counter_t> counters;
  RpcServer server(*bus, area);
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
  std::fprintf(stderr, "sb_rpc_counter: serving %s on %s\n", rpc_request_channel(area).c_str(),
               bus->url().c_str());
  auto last = std::chrono::steady_clock::now();
  apps::stop_on_signals();  // stop cleanly and print the statistics
  while (!apps::stop_requested()) {
    if (bus->handle(std::chrono::milliseconds(100))) last = std::chrono::steady_clock::now();
    if (idle_ms >= 0 && std::chrono::steady_clock::now() - last > std::chrono::milliseconds(idle_ms)) break;
  }
  apps::Summary out;
  out["served"] = server.served();
  out["duplicates"] = server.duplicates();
  out["expired"] = server.expired();
  out["bad_input"] = server.bad_input().total();
  apps::print_summary(out);
  return 0;
}
