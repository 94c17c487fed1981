// Inverse kinematics with Ceres: a bounded least-squares problem on the tool pose error
// (position in m, orientation as a rotation vector in rad, weighted), the joint limits
// as bounds, seeded from the current joints, then from further seeds while it fails.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "skillbus/motion/kinematics.hpp"

namespace skillbus::motion {

struct IkResult {
  bool ok = false;
  Eigen::VectorXd q;
  double position_error = 0, orientation_error = 0;
  int seeds_tried = 0;
  std::string error;
};

struct IkOptions {
  double position_tolerance = 1e-3;      // m
  double orientation_tolerance = 1e-2;   // rad
  int max_iterations = 100;
};

IkResult solve_ik(const Kinematics& k, const Eigen::Isometry3d& target, const Eigen::VectorXd& seed,
                  const IkOptions& opt = {});

// The error of the tool at q against target: (position m, orientation rad).
std::pair<double, double> pose_error(const Kinematics& k, const Eigen::VectorXd& q, const Eigen::Isometry3d& target);

}  // namespace skillbus::motion
