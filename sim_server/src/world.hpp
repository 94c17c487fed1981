// Private to sim_physics (DART): the DART world of a scene and the robot's set-up in it.
// Only the physics' own .cpp files include this; DART stays out of the public headers.
#pragma once

#include <Eigen/Geometry>
#include <dart/dynamics/SmartPointer.hpp>
#include <dart/simulation/SmartPointer.hpp>
#include <functional>
#include <string>
#include <vector>

#include "skillbus/scene/scene.hpp"
#include "skillbus/sim/finger_controller.hpp"
#include "skillbus/sim/trajectory.hpp"

namespace skillbus::sim {

// The world as built from a scene.
struct World {
  dart::simulation::WorldPtr sim;
  std::vector<dart::dynamics::SkeletonPtr> robots;  // in scene order
  std::vector<dart::dynamics::SkeletonPtr> objects;
  std::vector<dart::dynamics::SkeletonPtr> articulated;  // in scene order
  // Digest order: floor, fixtures, robots, objects, articulated objects (last, so that a
  // scene without them digests as before).
  std::vector<dart::dynamics::SkeletonPtr> all;
};

// Builds the world: the constraint solver and collision detector the scene names, the
// floor, the fixtures and the robots (URDF), then the objects, then the articulated
// objects (URDF, root link fixed, passive joints; throws scene::SceneError naming the
// field when a joint the scene names is not a 1-DoF prismatic or revolute joint of the
// URDF, or an initial position is outside its limits). `set_up_robot` is called
// with each robot's index in the scene once it is loaded, before the objects are made and
// anything is added to the world. Throws scene::SceneError when the scene cannot be built.
World build_world(const scene::Scene& scene,
                  const std::function<void(size_t index, dart::dynamics::Skeleton& robot)>& set_up_robot);

// The robot's layout as the controllers see it.
struct RobotLayout {
  std::vector<size_t> arm_dofs;  // skeleton DoF indices of the arm's joints, in skeleton order
  std::vector<std::string> arm_names;
  std::vector<JointLimits> arm_limits;
  size_t left_dof = 0, right_dof = 0;  // the fingers'
  FingerLimits finger_limits;          // the tighter of the two fingers'
  dart::dynamics::BodyNode* tool = nullptr;
};

// Checks a robot of the scene against its skeleton and sets it up: joint limits enforced,
// the initial joint positions, the fingers' friction. Throws scene::SceneError naming
// the field that does not fit the URDF.
RobotLayout set_up_robot(dart::dynamics::Skeleton& robot, const scene::Scene& scene, const scene::RobotSpec& spec);

// Between the scene's poses (x y z qx qy qz qw) and Eigen's.
Eigen::Isometry3d to_iso(const scene::Pose& p);
void from_iso(const Eigen::Isometry3d& T, double* out);

}  // namespace skillbus::sim
