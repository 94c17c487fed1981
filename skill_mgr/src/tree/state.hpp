// The state of a skill node, as SkiROS2 names it.
#pragma once

#include <string>

#include "skillbus_msgs/skill_state_t.hpp"

namespace skillbus::skills {

// The values are the IDL's (skill_state_t): a State travels as its number.
enum class State : int8_t {
  Uninitialized = skillbus_msgs::skill_state_t::UNINITIALIZED,
  Idle = skillbus_msgs::skill_state_t::IDLE,
  Running = skillbus_msgs::skill_state_t::RUNNING,
  Success = skillbus_msgs::skill_state_t::SUCCESS,
  Failure = skillbus_msgs::skill_state_t::FAILURE,
};

inline const char* to_string(State s) {
  switch (s) {
    case State::Uninitialized: return "Uninitialized";
    case State::Idle: return "Idle";
    case State::Running: return "Running";
    case State::Success: return "Success";
    case State::Failure: return "Failure";
  }
  return "?";
}

inline bool finished(State s) { return s == State::Success || s == State::Failure; }

}  // namespace skillbus::skills
