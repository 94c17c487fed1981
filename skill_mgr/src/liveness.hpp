// Liveness between the manager and its skill processes, on the wall clock (under lockstep
// the clock master names a participant that died):
//   * the manager announces itself on SB_SKILL_MANAGER every second, listing the
//     processes it knows (a process it does not list registers again);
//   * processes' heartbeats arrive on SB_SKILL_HEARTBEAT; a process silent for the
//     liveness timeout is removed from the registry, with the reason kept for the tasks
//     that need its skills.
#pragma once

#include <chrono>
#include <map>
#include <string>

#include "registry.hpp"
#include "skillbus/bus.hpp"

namespace skillbus::skills {

class Liveness {
 public:
  Liveness(Bus& bus, Registry& registry, std::string manager_name, std::chrono::milliseconds timeout);
  ~Liveness() { bus_.unsubscribe(subscription_); }
  Liveness(const Liveness&) = delete;
  Liveness& operator=(const Liveness&) = delete;
  void registered(const std::string& process);  // a registration counts as a heartbeat
  void on_frame();                              // announce (once a second), drop the silent
  void announce();                              // once a second at most (also while a call waits)
  int64_t incarnation() const { return incarnation_; }

 private:
  void drop_silent();

  Bus& bus_;
  Registry& registry_;
  std::string name_;
  std::chrono::milliseconds timeout_;
  int64_t incarnation_ = 0;  // this run of the manager (an identity, not behaviour)
  std::map<std::string, std::chrono::steady_clock::time_point> heard_from_;  // process -> last heartbeat
  std::chrono::steady_clock::time_point last_announce_{};
  std::chrono::steady_clock::time_point last_check_;  // drop_silent's last run (first: the manager's start)
  int subscription_ = -1;
};

}  // namespace skillbus::skills
