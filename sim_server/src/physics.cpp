#include "skillbus/sim/physics.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <dart/collision/CollisionObject.hpp>
#include <dart/collision/CollisionResult.hpp>
#include <dart/constraint/ConstraintSolver.hpp>
#include <dart/constraint/WeldJointConstraint.hpp>
#include <dart/dynamics/BodyNode.hpp>
#include <dart/dynamics/DegreeOfFreedom.hpp>
#include <dart/dynamics/ShapeNode.hpp>
#include <dart/dynamics/Skeleton.hpp>
#include <dart/simulation/World.hpp>

#include "physics_impl.hpp"

namespace skillbus::sim {

void Physics::Impl::build() {
  steps_since_build = 0;
  attachments.clear();  // (their welds go with the old world's constraint solver)
  robots.clear();
  robots.resize(scene.robots.size());
  world = build_world(scene, [&](size_t index, dart::dynamics::Skeleton& robot) {
    RobotRig& rig = robots[index];
    rig.spec = &scene.robots[index];
    rig.layout = set_up_robot(robot, scene, *rig.spec);
    std::vector<double> arm_positions;
    for (size_t d : rig.layout.arm_dofs) arm_positions.push_back(robot.getPosition(d));
    rig.arm = ArmController(rig.layout.arm_names, rig.layout.arm_limits, std::move(arm_positions), step_ns);
    const double opening = 0.5 * (robot.getPosition(rig.layout.left_dof) + robot.getPosition(rig.layout.right_dof));
    const double finger_mass = robot.getMassMatrix()(rig.layout.left_dof, rig.layout.left_dof);
    rig.fingers = FingerController(rig.layout.finger_limits, finger_mass, step_ns, opening);
  });
  obstacles.clear();
  obstacle_contact_steps.resize(scene.fixtures.size(), 0);
  for (size_t f = 0; f < scene.fixtures.size(); ++f)  // world.all: the floor, then the fixtures in scene order
    if (scene.fixtures[f].obstacle) obstacles.emplace_back(world.all[1 + f].get(), f);
  for (size_t i = 0; i < robots.size(); ++i) {
    robots[i].skeleton = world.robots[i];
    robots[i].applied = Eigen::VectorXd::Zero(world.robots[i]->getNumDofs());
  }
  build_cameras();
}

void RobotRig::control(int64_t total_steps) {
  dart::dynamics::Skeleton& robot = *skeleton;
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

double RobotRig::opening() const {
  return 0.5 * (skeleton->getPosition(layout.left_dof) + skeleton->getPosition(layout.right_dof));
}

void Physics::Impl::step() {
  for (RobotRig& r : robots) r.control(total_steps);
  const auto t0 = std::chrono::steady_clock::now();
  world.sim->step();
  physics_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ++total_steps;
  ++steps_since_build;
  for (RobotRig& r : robots) r.arm.finish_step(total_steps);
  if (robots.size() > 1 || !obstacles.empty()) count_contacts();
}

// Two robots touching, or a robot touching an obstacle, is a collision the skills and the
// motion planner should never cause: counted (steps with at least one such contact), so
// that a run can show there was none.
void Physics::Impl::count_contacts() {
  bool robots_touched = false;
  std::vector<bool> touched(obstacles.size(), false);
  auto is_robot = [&](const dart::dynamics::Skeleton* s) {
    for (const auto& r : world.robots)
      if (r.get() == s) return true;
    return false;
  };
  auto obstacle_of = [&](const dart::dynamics::Skeleton* s) -> int {
    for (size_t k = 0; k < obstacles.size(); ++k)
      if (obstacles[k].first == s) return static_cast<int>(k);
    return -1;
  };
  for (const auto& c : world.sim->getLastCollisionResult().getContacts()) {
    const auto* a = c.collisionObject1->getShapeFrame()->asShapeNode()->getBodyNodePtr()->getSkeleton().get();
    const auto* b = c.collisionObject2->getShapeFrame()->asShapeNode()->getBodyNodePtr()->getSkeleton().get();
    if (a == b) continue;
    const bool ra = is_robot(a), rb = is_robot(b);
    robots_touched = robots_touched || (ra && rb);
    if (ra != rb) {
      const int k = obstacle_of(ra ? b : a);
      if (k >= 0) touched[static_cast<size_t>(k)] = true;
    }
  }
  if (robots_touched) ++robot_contact_steps;
  for (size_t k = 0; k < obstacles.size(); ++k)
    if (touched[k]) ++obstacle_contact_steps[obstacles[k].second];
}

RobotRig& Physics::Impl::rig(size_t robot) {
  return const_cast<RobotRig&>(static_cast<const Impl*>(this)->rig(robot));
}

const RobotRig& Physics::Impl::rig(size_t robot) const {
  if (robot >= robots.size())
    throw std::out_of_range("robot " + std::to_string(robot) + ": the scene has " + std::to_string(robots.size()));
  return robots[robot];
}

Physics::Physics(const scene::Scene& scene) : impl_(std::make_unique<Impl>()) {
  impl_->scene = scene;
  impl_->step_ns = static_cast<int64_t>(std::llround(scene.physics.step_ms * 1e6));
  impl_->steps_per_frame = static_cast<int>(std::llround(scene.physics.frame_ms / scene.physics.step_ms));
  impl_->build();
}

Physics::~Physics() = default;

void Physics::reset() { impl_->build(); }

std::string Physics::command_arm(size_t robot, const ArmCommand& cmd) {
  return impl_->rig(robot).arm.command(cmd, impl_->total_steps);
}

std::string Physics::command_gripper(size_t robot, const GripperCommand& cmd) {
  RobotRig& r = impl_->rig(robot);
  return r.fingers.command(cmd, r.opening());
}

namespace {
constexpr double kAttachReach = 0.10;  // m: attach takes an object this near the tool centre point
}

std::string Physics::attach(size_t robot, const std::string& object, bool attach) {
  Impl& m = *impl_;
  const RobotRig& r = m.rig(robot);
  auto& attachments = m.attachments;
  auto drop = [&](std::vector<Attachment>::iterator it) {
    m.world.sim->getConstraintSolver()->removeConstraint(it->weld);
    return attachments.erase(it);
  };
  if (!attach && object.empty()) {  // let go of everything this robot holds
    for (auto it = attachments.begin(); it != attachments.end();) it = it->robot == robot ? drop(it) : it + 1;
    return "";
  }
  const auto& objects = m.world.objects;
  size_t k = 0;
  while (k < objects.size() && objects[k]->getName() != object) ++k;
  if (k == objects.size()) {
    std::string known;
    for (const auto& o : objects) known += (known.empty() ? "" : ", ") + o->getName();
    return "unknown object '" + object + "' (the scene's objects: " + (known.empty() ? "none" : known) + ")";
  }
  const auto held = std::find_if(attachments.begin(), attachments.end(), [&](const Attachment& a) { return a.object == k; });
  if (!attach) {
    if (held == attachments.end()) return "";  // not attached: nothing to do
    if (held->robot != robot)
      return "object '" + object + "' is attached to " + m.robots[held->robot].spec->name + ", not to " + r.spec->name;
    drop(held);
    return "";
  }
  if (held != attachments.end())
    return "object '" + object + "' is already attached to " + m.robots[held->robot].spec->name;
  double tcp[7];
  r.tool_pose(tcp);
  dart::dynamics::BodyNode* body = objects[k]->getRootBodyNode();
  const double distance = (body->getWorldTransform().translation() - Eigen::Vector3d(tcp[0], tcp[1], tcp[2])).norm();
  if (distance > kAttachReach) {
    char d[32];
    std::snprintf(d, sizeof d, "%.2f", distance);
    if (std::string(d) == "0.10") std::snprintf(d, sizeof d, "%.4f", distance);  // (just beyond: say by how much)
    return "object '" + object + "' is " + d + " m from the tool centre point of " + r.spec->name +
           ": attach needs it within 0.10 m";
  }
  // The weld holds the object's pose relative to the tool link as it is now.
  auto weld = std::make_shared<dart::constraint::WeldJointConstraint>(body, r.layout.tool);
  m.world.sim->getConstraintSolver()->addConstraint(weld);
  attachments.push_back({robot, k, weld});
  return "";
}

void Physics::step_frame() {
  for (int i = 0; i < impl_->steps_per_frame; ++i) impl_->step();
}

const scene::Scene& Physics::scene() const { return impl_->scene; }
int Physics::steps_per_frame() const { return impl_->steps_per_frame; }
int64_t Physics::step_count() const { return impl_->total_steps; }
std::string Physics::collision_detector() const { return impl_->scene.physics.collision_detector; }
double Physics::physics_seconds() const { return impl_->physics_seconds; }
size_t Physics::num_robots() const { return impl_->robots.size(); }
int64_t Physics::robot_contact_steps() const { return impl_->robot_contact_steps; }

std::vector<std::pair<std::string, int64_t>> Physics::obstacle_contact_steps() const {
  std::vector<std::pair<std::string, int64_t>> out;
  for (size_t f = 0; f < impl_->scene.fixtures.size(); ++f)
    if (impl_->scene.fixtures[f].obstacle) out.emplace_back(impl_->scene.fixtures[f].name, impl_->obstacle_contact_steps[f]);
  return out;
}

}  // namespace skillbus::sim
