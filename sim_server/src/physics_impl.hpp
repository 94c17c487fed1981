// Private to sim_physics (DART): the state behind Physics' pimpl, shared by physics.cpp
// (building, control, stepping, commands) and state.cpp (the state messages, the digest).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "skillbus/scene/scene.hpp"
#include "skillbus/sim/arm_controller.hpp"
#include "skillbus/sim/finger_controller.hpp"
#include "skillbus/sim/physics.hpp"
#include "world.hpp"

namespace skillbus::sim {

struct Physics::Impl {
  scene::Scene scene;
  World world;
  RobotLayout layout;
  ArmController arm;
  FingerController fingers;
  Eigen::VectorXd applied;   // forces applied in the last step
  int steps_per_frame = 10;
  int64_t step_ns = 1'000'000;
  int64_t total_steps = 0;   // since start (never reset): the time base of trajectories
  int64_t steps_since_build = 0;  // no step yet: no contacts to read supports from
  double physics_seconds = 0;

  void build();    // the world and the controllers from the scene (again on reset)
  void control();  // the controllers' forces for the next step
  void step();
  // For the state messages (state.cpp):
  void tool_pose(double* out) const;  // the tool centre point (world): x y z qx qy qz qw
  double tracking_error() const;      // rad, max |reference - position| over the arm joints
  std::vector<std::string> supports() const;  // per object: what it rests on (state.cpp)
};

}  // namespace skillbus::sim
