// What the nodes of one task share: the registry, the task's blackboard, RPC clients to
// the skill processes, the world replica, and the frame being ticked.
#pragma once

#include <array>
#include <chrono>
#include <functional>
#include <string>

#include "blackboard.hpp"
#include "registry.hpp"
#include "skillbus/rpc.hpp"
#include "world_replica.hpp"

namespace skillbus::skills {

struct TaskContext {
  const Registry& registry;
  Blackboard& blackboard;
  std::function<RpcClient&(const std::string& area)> client;  // one RPC client per skill process
  std::chrono::milliseconds tick_timeout{1000};
  int64_t next_instance = 1;
  WorldReplica* world = nullptr;  // for conditions and grounding
  std::string robot;              // the agent this manager drives: every skill's Robot parameter
  // The label of that agent (a skiros:Robot) when only its name is known (--robot NAME):
  // its id is looked up in the world replica once the replica is there.
  std::string robot_label;
  int64_t frame = -1;             // the frame being ticked, passed to skill processes
  int64_t sim_time_ns = 0;
  std::chrono::milliseconds expand_timeout{30000};  // a compound's expansion (ManagerOptions)
  int64_t* idle_ticks = nullptr;  // the manager's count of execute ticks skipped (idle_until_ns)
  // The manager's count of the ticks it sent, by action (skill_tick_t: START, EXECUTE,
  // PREEMPT, END); an END only where no reply said the instance ended.
  std::array<int64_t, 4>* ticks_sent = nullptr;
};

// The replica when it is loaded, else null (reads that may go without a world).
const wm::WorldStore* world_if_ready(TaskContext& ctx);
// The replica, fetched now if needed; null, with `why`, when no world model answers.
const wm::WorldStore* world_for(TaskContext& ctx, std::string* why);

}  // namespace skillbus::skills
