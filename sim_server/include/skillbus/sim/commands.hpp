// Arm, finger and attach commands as the physics takes them (decoded from
// robot_arm_cmd_t, sim_gripper_cmd_t and sim_attach_t, or read from a script).
#pragma once

#include <string>
#include <vector>

#include "skillbus/sim/trajectory.hpp"

namespace skillbus::sim {

struct ArmCommand {
  std::string id;
  std::vector<std::string> joints;
  std::vector<Waypoint> points;
};

struct GripperCommand {
  std::string id;
  double width = 0, speed = 0, force_limit = 0;
};

// Attach an object to the robot's tool, or detach it ("" detaches every object).
struct AttachCommand {
  std::string id;
  bool attach = true;
  std::string object;
};

}  // namespace skillbus::sim
