// Joint trajectories for the arm: to a tool pose in joint space (one timed segment), or
// along a straight line of the tool (IK every step_m, each seeded by the last), timed so
// that no joint exceeds speed_scale of its velocity limit.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "skillbus/motion/ik.hpp"

namespace skillbus::motion {

struct PlanRequest {
  Eigen::VectorXd start;
  Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
  bool cartesian = false;
  double step_m = 0.01;
  double speed_scale = 0.5;
};

struct Plan {
  bool ok = false;
  std::string error;
  Eigen::VectorXd goal;
  std::vector<std::pair<int64_t, Eigen::VectorXd>> points;  // (ns from start, joints)
  double position_error = 0, orientation_error = 0;
  int seeds_tried = 0;
};

Plan plan_motion(const Kinematics& k, const PlanRequest& req);

}  // namespace skillbus::motion
