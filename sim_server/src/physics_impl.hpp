// Private to sim_physics (DART): the state behind Physics' pimpl, shared by physics.cpp
// (building, control, stepping, commands) and state.cpp (the state messages, the digest).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <dart/constraint/SmartPointer.hpp>
#include <string>
#include <vector>

#include "skillbus/scene/scene.hpp"
#include "skillbus/sim/arm_controller.hpp"
#include "skillbus/sim/finger_controller.hpp"
#include "skillbus/sim/physics.hpp"
#include "world.hpp"

namespace skillbus::sim {

// One robot of the scene: its skeleton's layout, its controllers, the forces applied to
// it in the last step.
struct RobotRig {
  const scene::RobotSpec* spec = nullptr;  // in Impl::scene, which never changes after construction
  dart::dynamics::SkeletonPtr skeleton;
  RobotLayout layout;
  ArmController arm;
  FingerController fingers;
  Eigen::VectorXd applied;

  void control(int64_t total_steps);  // the controllers' forces for the next step
  void tool_pose(double* out) const;  // the tool centre point (world): x y z qx qy qz qw
  double tracking_error(int64_t total_steps) const;  // rad, max |reference - position| over the arm joints
  double opening() const;             // m, the mean of the two fingers' positions
};

// A depth camera of the scene: where it is (fixed, or on a robot's link).
struct CameraRig {
  const scene::CameraSpec* spec = nullptr;  // in Impl::scene
  dart::dynamics::BodyNode* link = nullptr;  // null: fixed in the world
  Eigen::Isometry3d mount = Eigen::Isometry3d::Identity();  // world pose, or pose on the link
};

// An object welded to a robot's tool link (Physics::attach): the weld is in the world's
// constraint solver until detached or the world is rebuilt.
struct Attachment {
  size_t robot = 0;
  size_t object = 0;  // index in World::objects
  dart::constraint::ConstraintBasePtr weld;
};

struct Physics::Impl {
  scene::Scene scene;
  World world;
  std::vector<RobotRig> robots;  // in scene order
  int steps_per_frame = 10;
  int64_t step_ns = 1'000'000;
  int64_t total_steps = 0;   // since start (never reset): the time base of trajectories
  int64_t steps_since_build = 0;  // no step yet: no contacts to read supports from
  int64_t robot_contact_steps = 0;  // steps in which two robots touched (never reset)
  // The scene's obstacles (fixtures from its "obstacles" list): skeleton -> fixture index,
  // and per fixture the steps in which a robot touched it (never reset).
  std::vector<std::pair<const dart::dynamics::Skeleton*, size_t>> obstacles;
  std::vector<int64_t> obstacle_contact_steps;
  double physics_seconds = 0;
  std::vector<CameraRig> cameras;  // in scene order
  std::vector<Attachment> attachments;  // in the order they were made

  void build();    // the world and the controllers from the scene (again on reset)
  void step();
  void build_cameras();  // after the world (camera.cpp)
  void count_contacts();  // after a step, with several robots or with obstacles
  RobotRig& rig(size_t robot);  // throws std::out_of_range naming the robots there are
  const RobotRig& rig(size_t robot) const;
  // For the state messages (state.cpp): per object, what it rests on (from the last
  // step's contacts, or held by the gripper of the robot it is attached to).
  std::vector<std::string> supports() const;
  std::vector<std::string> contact_supports() const;
};

}  // namespace skillbus::sim
