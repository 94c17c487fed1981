// The arm's kinematics from the scene's robot (URDF through DART): forward kinematics of
// the tool centre point and its Jacobian, over the arm joints (the finger joints are not
// part of the arm). DART stays in kinematics.cpp.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "skillbus/scene/scene.hpp"

namespace skillbus::motion {

struct JointInfo {
  std::string name;
  double lower, upper, velocity;
};

class Kinematics {
 public:
  // The robot of the scene with that bus name ("": the one robot of a one-robot scene);
  // throws scene::SceneError (no such robot, a URDF that does not fit).
  explicit Kinematics(const scene::Scene& scene, const std::string& robot = "");
  ~Kinematics();
  const std::vector<JointInfo>& joints() const { return joints_; }
  Eigen::Isometry3d tool_pose(const Eigen::VectorXd& q) const;
  // Where the robot stands (its URDF's root link in the world): a target's direction
  // from the robot is taken in this frame, not the world's.
  const Eigen::Isometry3d& base() const { return base_; }
  // 6 x n: rows 0-2 linear velocity of the tool point, rows 3-5 angular, world frame.
  Eigen::MatrixXd jacobian(const Eigen::VectorXd& q) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<JointInfo> joints_;
  Eigen::Isometry3d base_ = Eigen::Isometry3d::Identity();
};

}  // namespace skillbus::motion
