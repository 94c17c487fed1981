#include "skillbus/motion/kinematics.hpp"

#include <dart/dynamics/BodyNode.hpp>
#include <dart/dynamics/DegreeOfFreedom.hpp>
#include <dart/dynamics/Joint.hpp>
#include <dart/dynamics/Skeleton.hpp>
#include <dart/utils/urdf/DartLoader.hpp>

namespace skillbus::motion {

struct Kinematics::Impl {
  dart::dynamics::SkeletonPtr robot;
  dart::dynamics::BodyNode* tool = nullptr;
  Eigen::Vector3d offset;
  std::vector<size_t> dofs;

  void set(const Eigen::VectorXd& q) const {
    for (size_t k = 0; k < dofs.size(); ++k) robot->setPosition(dofs[k], q[static_cast<Eigen::Index>(k)]);
  }
};

Kinematics::Kinematics(const scene::Scene& scene, const std::string& robot) : impl_(std::make_unique<Impl>()) {
  const scene::RobotSpec& r = scene::robot_on_bus(scene, robot);
  dart::utils::DartLoader loader;
  impl_->robot = loader.parseSkeleton(dart::common::Uri::createFromPath(r.urdf), nullptr,
                                      dart::utils::DartLoader::FIXED_BASE_LINK);
  if (!impl_->robot) throw scene::SceneError(r.urdf + ": DART cannot load this URDF");
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.translation() = Eigen::Vector3d(r.pose[0], r.pose[1], r.pose[2]);
  base.linear() = Eigen::Quaterniond(r.pose[6], r.pose[3], r.pose[4], r.pose[5]).normalized().toRotationMatrix();
  impl_->robot->getRootJoint()->setTransformFromParentBodyNode(base);
  base_ = base;
  impl_->tool = impl_->robot->getBodyNode(r.tool_link);
  if (!impl_->tool) throw scene::SceneError(scene.path + ": robot " + r.name + ": tool_link '" + r.tool_link + "' is not a link");
  impl_->offset = Eigen::Vector3d(0, 0, r.tool_offset);
  for (size_t i = 0; i < impl_->robot->getNumDofs(); ++i) {
    auto* dof = impl_->robot->getDof(i);
    const std::string name = dof->getJoint()->getName();
    if (name == r.left_finger_joint || name == r.right_finger_joint) continue;
    impl_->dofs.push_back(i);
    joints_.push_back({name, dof->getPositionLowerLimit(), dof->getPositionUpperLimit(), dof->getVelocityUpperLimit()});
  }
}

Kinematics::~Kinematics() = default;

Eigen::Isometry3d Kinematics::tool_pose(const Eigen::VectorXd& q) const {
  impl_->set(q);
  Eigen::Isometry3d T = impl_->tool->getWorldTransform();
  T.translate(impl_->offset);
  return T;
}

Eigen::MatrixXd Kinematics::jacobian(const Eigen::VectorXd& q) const {
  impl_->set(q);
  const Eigen::MatrixXd full = impl_->robot->getWorldJacobian(impl_->tool, impl_->offset);  // angular; linear
  Eigen::MatrixXd J(6, static_cast<Eigen::Index>(impl_->dofs.size()));
  for (size_t k = 0; k < impl_->dofs.size(); ++k) {
    const auto c = static_cast<Eigen::Index>(impl_->dofs[k]);
    J.block<3, 1>(0, static_cast<Eigen::Index>(k)) = full.block<3, 1>(3, c);
    J.block<3, 1>(3, static_cast<Eigen::Index>(k)) = full.block<3, 1>(0, c);
  }
  return J;
}

}  // namespace skillbus::motion
