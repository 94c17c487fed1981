// The state of a skill node, as SkiROS2 names it.
#pragma once

#include <string>

namespace skillbus::skills {

enum class State { Uninitialized, Idle, Running, Success, Failure };

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
