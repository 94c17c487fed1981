// The round trip of one Python primitive tick through the skill manager's machinery:
// a RemotePrimitive node (the manager's own code) ticking a primitive served by a real
// skill process over LCM. No manager: the process (skills-process --standalone) is put in
// this program's own registry, as a registration would (a node fails a process the
// registry does not know: its heartbeats stopped).
// Usage: tick_rtt_bench AREA LABEL TICKS      prints JSON with the median and p99 in us
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "remote_primitive.hpp"
#include "skillbus_msgs/skill_register_t.hpp"

using namespace skillbus;
using namespace skillbus::skills;

int main(int argc, char** argv) {
  if (argc < 4) return 2;
  auto bus = open_bus();
  Registry registry;
  Blackboard bb;
  RpcClient client(*bus, argv[1], "bench");
  TaskContext ctx{registry, bb, [&](const std::string&) -> RpcClient& { return client; }, std::chrono::milliseconds(2000),
                  1, nullptr, "", ""};
  Implementation impl;
  impl.description.type = "Spin";
  impl.description.label = argv[2];
  impl.process = "bench";
  impl.rpc_area = argv[1];
  impl.incarnation = 1;
  skillbus_msgs::skill_register_t reg{};
  reg.process = impl.process;
  reg.rpc_area = impl.rpc_area;
  reg.incarnation = impl.incarnation;
  reg.skills = {impl.description};
  reg.num_skills = 1;
  registry.add(reg);
  RemotePrimitive node(ctx, impl, std::make_shared<Scope>());
  const int ticks = std::atoi(argv[3]);
  std::vector<double> us;
  for (int i = 0; i < ticks + 50; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const State s = node.tick();
    const double d = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
    if (s == State::Failure) {
      std::printf("{\"error\": \"%s\"}\n", node.message().c_str());
      return 1;
    }
    if (i >= 50) us.push_back(d);  // after warm-up
  }
  std::sort(us.begin(), us.end());
  std::printf("{\"ticks\": %d, \"median_us\": %.1f, \"p99_us\": %.1f}\n", ticks, us[us.size() / 2],
              us[static_cast<size_t>(us.size() * 0.99)]);
  node.preempt();
  return 0;
}
