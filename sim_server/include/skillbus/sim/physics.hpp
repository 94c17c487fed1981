// The simulated robots and world: a DART world built from a scene file, each arm's joint
// controller (arm_controller.hpp: computed torque with PID on a joint trajectory) and the
// finger controller (finger_controller.hpp: position ramp with a force limit), stepped a
// frame at a time. DART stays behind this header (pimpl) so nothing else compiles it:
// src/world.* builds the world and sets up the robot, src/physics.cpp controls and
// steps it, src/state.cpp reads the state messages and the digest out of it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "skillbus/digest.hpp"
#include "skillbus/scene/scene.hpp"
#include "skillbus/sim/camera.hpp"
#include "skillbus/sim/commands.hpp"
#include "skillbus_msgs/articulation_state_t.hpp"
#include "skillbus_msgs/robot_arm_state_t.hpp"
#include "skillbus_msgs/robot_objects_t.hpp"
#include "skillbus_msgs/sim_state_t.hpp"

namespace skillbus::sim {

class Physics {
 public:
  explicit Physics(const scene::Scene& scene);  // throws scene::SceneError when the scene cannot be built
  ~Physics();
  Physics(const Physics&) = delete;
  Physics& operator=(const Physics&) = delete;

  // Back to the scene's initial state (time keeps running; the world restarts).
  void reset();

  // Robots are numbered in scene order (scene().robots); every per-robot call throws
  // std::out_of_range for a number the scene does not have.
  size_t num_robots() const;

  // Validate and take a command for a robot; the error (empty when accepted) names what
  // was wrong. A rejected command changes nothing: the robot holds its targets.
  std::string command_arm(size_t robot, const ArmCommand& cmd);
  std::string command_gripper(size_t robot, const GripperCommand& cmd);
  // Attach (weld) one of the scene's free objects to a robot's tool link where it is now,
  // or let it go: "" when done, else why not (nothing changes). Attaching needs the
  // object within 0.10 m of the tool centre point and not attached already; detaching
  // `object` "" lets go of every object attached to that robot, and detaching an object
  // that is not attached is accepted. A reset drops every attachment.
  std::string attach(size_t robot, const std::string& object, bool attach);

  void step_frame();  // frame_ms / step_ms physics steps with the controllers
  // The simulator's ground truth for a robot (SB_SIM_STATE): every joint of that robot,
  // its fingers, the objects, its fingers' contacts.
  void fill_state(size_t robot, skillbus_msgs::sim_state_t& out) const;
  // A robot as a real arm's driver would report it (SB_ROBOT_ARM_STATE): the arm's
  // joints only, the tool pose, the trajectory being tracked.
  void fill_arm_state(size_t robot, skillbus_msgs::robot_arm_state_t& out) const;
  // A perfect camera (SB_ROBOT_OBJECTS): every free object's name, exact pose and what it
  // rests on (a fixture, or the gripper that holds it, by their world-model labels).
  void fill_objects(skillbus_msgs::robot_objects_t& out) const;
  // The articulated objects' joints (SB_ROBOT_ARTICULATION): every joint the scene's
  // articulated objects list, in scene order of the objects, then by joint name: position,
  // velocity, limits, the axis and a point on it (world), and where the tool grasps its
  // handle now (world). No joints for a scene without articulated objects.
  void fill_articulation(size_t robot, skillbus_msgs::articulation_state_t& out) const;
  // The scene's depth cameras (scene().cameras, in order). A capture casts a ray per pixel
  // against the world as it is now; `capture_index` picks the noise (the same index gives
  // the same cloud). Throws std::out_of_range for a camera the scene does not have.
  size_t num_cameras() const;
  DepthCapture capture(size_t camera, int64_t capture_index);
  // SHA-256 over every skeleton's positions and velocities (bit patterns), in scene order.
  Digest digest() const;

  const scene::Scene& scene() const;
  int steps_per_frame() const;
  int64_t step_count() const;
  std::string collision_detector() const;
  double physics_seconds() const;  // wall time spent inside DART's step (benchmarks only)
  // Steps in which two robots touched (only counted with several robots; never reset).
  int64_t robot_contact_steps() const;
  // Per obstacle of the scene (its "obstacles" list), in scene order: the steps in which a
  // robot touched it (never reset).
  std::vector<std::pair<std::string, int64_t>> obstacle_contact_steps() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace skillbus::sim
