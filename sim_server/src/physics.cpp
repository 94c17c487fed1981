#include "skillbus/sim/physics.hpp"

#include <chrono>
#include <cmath>
#include <dart/dynamics/DegreeOfFreedom.hpp>
#include <dart/dynamics/Skeleton.hpp>
#include <dart/simulation/World.hpp>

#include "physics_impl.hpp"

namespace skillbus::sim {

void Physics::Impl::build() {
  steps_since_build = 0;
  world = build_world(scene, [&](dart::dynamics::Skeleton& robot) {
    layout = set_up_robot(robot, scene);
    std::vector<double> arm_positions;
    for (size_t d : layout.arm_dofs) arm_positions.push_back(robot.getPosition(d));
    arm = ArmController(layout.arm_names, layout.arm_limits, std::move(arm_positions), step_ns);
    const double opening = 0.5 * (robot.getPosition(layout.left_dof) + robot.getPosition(layout.right_dof));
    const double finger_mass = robot.getMassMatrix()(layout.left_dof, layout.left_dof);
    fingers = FingerController(layout.finger_limits, finger_mass, step_ns, opening);
  });
  applied = Eigen::VectorXd::Zero(world.robot->getNumDofs());
}

void Physics::Impl::control() {
  dart::dynamics::Skeleton& robot = *world.robot;
  const Eigen::VectorXd q = robot.getPositions();
  const Eigen::VectorXd dq = robot.getVelocities();
  Eigen::VectorXd acc = Eigen::VectorXd::Zero(robot.getNumDofs());
  const std::vector<size_t>& arm_dofs = layout.arm_dofs;
  std::vector<double> arm_q(arm_dofs.size()), arm_dq(arm_dofs.size());
  for (size_t k = 0; k < arm_dofs.size(); ++k) {
    arm_q[k] = q[arm_dofs[k]];
    arm_dq[k] = dq[arm_dofs[k]];
  }
  const std::vector<double> arm_acc = arm.accelerations(total_steps, arm_q, arm_dq);
  for (size_t k = 0; k < arm_dofs.size(); ++k) acc[arm_dofs[k]] = arm_acc[k];
  // tau = M(q) acc + C(q, dq) + g(q) by recursive Newton-Euler: O(n), where forming M
  // costs O(n^2) every step. The accelerations set here are overwritten by the step.
  robot.setAccelerations(acc);
  robot.computeInverseDynamics(false, false, false);
  const Eigen::VectorXd tau = robot.getForces();
  for (size_t i : arm_dofs) {
    auto* dof = robot.getDof(i);
    applied[i] = ArmController::joint_force(tau[i], dof->getDampingCoefficient(), dq[i], dof->getForceLowerLimit(),
                                            dof->getForceUpperLimit());
  }
  const size_t left = layout.left_dof, right = layout.right_dof;
  const FingerController::Forces f = fingers.update(q[left], q[right], dq[left], dq[right]);
  for (size_t i : {left, right}) {
    auto* dof = robot.getDof(i);
    applied[i] = FingerController::finger_force(f, i == left, tau[i], dof->getDampingCoefficient(), dq[i],
                                                dof->getForceLowerLimit(), dof->getForceUpperLimit());
  }
  robot.setForces(applied);
}

void Physics::Impl::step() {
  control();
  const auto t0 = std::chrono::steady_clock::now();
  world.sim->step();
  physics_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ++total_steps;
  ++steps_since_build;
  arm.finish_step(total_steps);
}

Physics::Physics(const scene::Scene& scene) : impl_(std::make_unique<Impl>()) {
  impl_->scene = scene;
  impl_->step_ns = static_cast<int64_t>(std::llround(scene.physics.step_ms * 1e6));
  impl_->steps_per_frame = static_cast<int>(std::llround(scene.physics.frame_ms / scene.physics.step_ms));
  impl_->build();
}

Physics::~Physics() = default;

void Physics::reset() { impl_->build(); }

std::string Physics::command_arm(const ArmCommand& cmd) { return impl_->arm.command(cmd, impl_->total_steps); }

std::string Physics::command_gripper(const GripperCommand& cmd) {
  const Impl& m = *impl_;
  const double opening = 0.5 * (m.world.robot->getPosition(m.layout.left_dof) + m.world.robot->getPosition(m.layout.right_dof));
  return impl_->fingers.command(cmd, opening);
}

void Physics::step_frame() {
  for (int i = 0; i < impl_->steps_per_frame; ++i) impl_->step();
}

const scene::Scene& Physics::scene() const { return impl_->scene; }
int Physics::steps_per_frame() const { return impl_->steps_per_frame; }
int64_t Physics::step_count() const { return impl_->total_steps; }
std::string Physics::collision_detector() const { return impl_->scene.physics.collision_detector; }
double Physics::physics_seconds() const { return impl_->physics_seconds; }

}  // namespace skillbus::sim
