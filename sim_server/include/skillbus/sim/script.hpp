// A command script played inside the physics server (--script FILE), in the format of
// `skillbus sim-script` (docs/sim_server.md): the same motions without any participant,
// for benchmarks of the physics alone and for quick experiments. Commands are due at
// frame boundaries, so a script gives the same run every time.
#pragma once

#include <string>
#include <vector>

#include "skillbus/scene/scene.hpp"
#include "skillbus/sim/commands.hpp"

namespace skillbus::sim {

struct ScriptStep {
  int64_t at_ns = 0;
  std::string robot;  // the robot's bus name ("robot" in the step; "" for a one-robot scene)
  bool is_arm = false;
  bool is_attach = false;  // neither: a gripper step
  ArmCommand arm;
  GripperCommand gripper;
  AttachCommand attach;
};

// Throws scene::SceneError naming the file and the step when the script is malformed.
std::vector<ScriptStep> load_script(const std::string& path);

}  // namespace skillbus::sim
