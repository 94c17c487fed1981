// Joint trajectories for the arm: to a tool pose in joint space, or along a straight line
// of the tool (IK every step_m, each seeded by the last), timed so that no joint exceeds
// speed_scale of its velocity limit. With a collision model, every trajectory is checked
// against it: a joint-space move whose straight joint segment would touch something goes
// around it (OMPL's RRTConnect, seeded and bounded in iterations, then shortcut), and a
// goal or a line that touches something fails naming what.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "skillbus/motion/collision.hpp"
#include "skillbus/motion/ik.hpp"

namespace skillbus::motion {

struct PlanRequest {
  Eigen::VectorXd start;
  Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
  bool cartesian = false;
  double step_m = 0.01;
  double speed_scale = 0.5;
  Eigen::Vector3d held = Eigen::Vector3d::Zero();  // sides of a box held at the tool (m); zero: none
};

struct PlannerOptions {
  uint32_t seed = 1;               // of the path search's sampler: the same request, the same path
  int max_iterations = 20000;      // of the path search: a bound in work, not in time
  double check_step = 0.01;        // rad: the largest joint change between two checked states
};

struct Plan {
  bool ok = false;
  std::string error;
  Eigen::VectorXd goal;
  std::vector<std::pair<int64_t, Eigen::VectorXd>> points;  // (ns from start, joints)
  double position_error = 0, orientation_error = 0;
  int seeds_tried = 0;
  // With a collision model: "direct" (the straight joint segment is clear), "around" (a
  // path search), "line" (cartesian); the search's iterations; whether the trajectory
  // rests at each point (a path around: its segments are straight in joint space only
  // when the arm stops at each corner).
  std::string how;
  int iterations = 0;
  bool rests_at_points = false;
};

// `world` null: no collision checks (the motions of a scene without one).
Plan plan_motion(const Kinematics& k, const PlanRequest& req, CollisionModel* world = nullptr,
                 const PlannerOptions& options = {});

}  // namespace skillbus::motion
