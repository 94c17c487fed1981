// How clients find every skill manager on a bus with several robots: a client publishes
// on the shared SB_MANAGERS_PROBE and every manager answers on the shared SB_MANAGERS
// with a skill_manager_info_t naming its robot (the namespace of its SKILL area). A
// manager also announces itself so at start. The answers are plain messages, outside
// the lockstep: no participant reads them, so they change nothing in a session.
#pragma once

#include <chrono>
#include <functional>

#include "skillbus/bus.hpp"
#include "skillbus_msgs/skill_manager_info_t.hpp"

namespace skillbus::skills {

std::string managers_probe_channel();  // SB_MANAGERS_PROBE
std::string managers_channel();        // SB_MANAGERS

class Directory {
 public:
  using Describe = std::function<skillbus_msgs::skill_manager_info_t()>;
  Directory(Bus& bus, Describe describe);
  ~Directory() { bus_.unsubscribe(subscription_); }
  Directory(const Directory&) = delete;
  Directory& operator=(const Directory&) = delete;

 private:
  void answer();

  Bus& bus_;
  Describe describe_;
  int subscription_ = -1;
  // Answers are at most 20 a second: every holder of the key may probe.
  std::chrono::steady_clock::time_point window_{};
  int answered_in_window_ = 0;
};

}  // namespace skillbus::skills
