// The demo scene's arm for the motion tests: the scene, its kinematics, its initial joints
// and top-down tool poses.
#pragma once

#include <Eigen/Geometry>
#include <cmath>

#include "skillbus/motion/kinematics.hpp"

namespace skillbus::motion::test {

inline const scene::Scene& demo_scene() {
  static const scene::Scene s = scene::load_scene(SKILLBUS_TEST_SCENE);
  return s;
}

inline Kinematics& kin() {
  static Kinematics k(demo_scene());
  return k;
}

// The scene's initial joints.
inline Eigen::VectorXd home() {
  Eigen::VectorXd q(6);
  q << 0.0, 0.2, 1.6, 0.0, 1.3416, 0.0;
  return q;
}

// Tool pointing down, fingers closing along the world axis at `yaw` from y.
inline Eigen::Isometry3d top_down(double x, double y, double z, double yaw = 0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, y, z);
  T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()))
                   .toRotationMatrix();
  return T;
}

}  // namespace skillbus::motion::test
