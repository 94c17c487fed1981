#include "physics.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <dart/collision/CollisionFilter.hpp>
#include <dart/collision/CollisionObject.hpp>
#include <dart/collision/CollisionResult.hpp>
#include <dart/collision/bullet/BulletCollisionDetector.hpp>
#include <dart/collision/dart/DARTCollisionDetector.hpp>
#include <dart/collision/fcl/FCLCollisionDetector.hpp>
#include <dart/constraint/BoxedLcpConstraintSolver.hpp>
#include <dart/constraint/ConstraintSolver.hpp>
#include <dart/constraint/DantzigBoxedLcpSolver.hpp>
#include <dart/constraint/PgsBoxedLcpSolver.hpp>
#include <dart/dynamics/BodyNode.hpp>
#include <dart/dynamics/BoxShape.hpp>
#include <dart/dynamics/CylinderShape.hpp>
#include <dart/dynamics/DegreeOfFreedom.hpp>
#include <dart/dynamics/FreeJoint.hpp>
#include <dart/dynamics/Joint.hpp>
#include <dart/dynamics/ShapeNode.hpp>
#include <dart/dynamics/Skeleton.hpp>
#include <dart/dynamics/WeldJoint.hpp>
#include <dart/simulation/World.hpp>
#include <dart/utils/urdf/DartLoader.hpp>
#include <map>
#include <set>

namespace skillbus::sim {

using namespace dart;
using dynamics::BodyNode;
using dynamics::SkeletonPtr;

namespace {

// Arm: computed torque with PID on the mass-normalised error, all three closed-loop
// poles at -25 rad/s (Kp = 3w^2, Kd = 3w, Ki = w^3); the integral takes up what the model
// does not know (a grasped object), bounded against wind-up. Fingers: critically
// damped at up to 200 rad/s, but never beyond 0.25 rad per step (the 50 g fingers are
// the stiffest part of the system: at 2 ms steps 200 rad/s would go unstable).
constexpr double kArmW = 25.0;
constexpr double kArmKp = 3 * kArmW * kArmW, kArmKd = 3 * kArmW, kArmKi = kArmW * kArmW * kArmW;
constexpr double kArmIntegralLimit = 0.05;  // rad s
constexpr double kFingerMaxW = 200.0, kFingerMaxWdt = 0.25;
constexpr double kFingerIntegralRate = 10.0;  // 1/s: Ki = Kp * rate
constexpr double kGripLag = 0.001, kGripStill = 0.002;  // m, m/s: blocked fingers (grip mode)
constexpr double kDefaultFingerSpeed = 0.1;   // m/s of the width
constexpr double kDefaultFingerForce = 20.0;  // N per finger
constexpr double kRobotFriction = 0.5, kFingerFriction = 1.0;

Eigen::Isometry3d to_iso(const Pose& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(p[0], p[1], p[2]);
  T.linear() = Eigen::Quaterniond(p[6], p[3], p[4], p[5]).normalized().toRotationMatrix();
  return T;
}

void from_iso(const Eigen::Isometry3d& T, double* out) {
  const Eigen::Quaterniond q(T.linear());
  out[0] = T.translation().x();
  out[1] = T.translation().y();
  out[2] = T.translation().z();
  out[3] = q.x();
  out[4] = q.y();
  out[5] = q.z();
  out[6] = q.w();
}

void set_friction(const SkeletonPtr& skel, double mu) {
  for (size_t b = 0; b < skel->getNumBodyNodes(); ++b)
    for (auto* sn : skel->getBodyNode(b)->getShapeNodesWith<dynamics::DynamicsAspect>())
      sn->getDynamicsAspect()->setFrictionCoeff(mu);
}

// Fixed fixtures never touch each other or the floor in a way that matters, and the
// robot's pedestal stands on the floor: skip those pairs before narrow phase.
class StaticPairFilter : public collision::CollisionFilter {
 public:
  explicit StaticPairFilter(std::set<const BodyNode*> fixed) : fixed_(std::move(fixed)) {}
  bool ignoresCollision(const collision::CollisionObject* a, const collision::CollisionObject* b) const override {
    const BodyNode* ba = a->getShapeFrame()->asShapeNode()->getBodyNodePtr().get();
    const BodyNode* bb = b->getShapeFrame()->asShapeNode()->getBodyNodePtr().get();
    if (ba->getSkeleton() == bb->getSkeleton() && !ba->getSkeleton()->isEnabledSelfCollisionCheck()) return true;
    return fixed_.count(ba) && fixed_.count(bb);
  }

 private:
  std::set<const BodyNode*> fixed_;
};

SkeletonPtr load_urdf(const std::string& path, const std::string& name, const Pose& pose) {
  utils::DartLoader loader;
  SkeletonPtr skel = loader.parseSkeleton(common::Uri::createFromPath(path), nullptr, utils::DartLoader::FIXED_BASE_LINK);
  if (!skel) throw SceneError(path + ": DART cannot load this URDF (see the log above)");
  skel->setName(name);
  skel->getRootJoint()->setTransformFromParentBodyNode(to_iso(pose));
  return skel;
}

}  // namespace

struct Physics::Impl {
  Scene scene;
  simulation::WorldPtr world;
  SkeletonPtr robot;
  std::vector<SkeletonPtr> objects;
  std::vector<SkeletonPtr> all;  // digest order: floor, fixtures, robot, objects
  int steps_per_frame = 10;
  int64_t step_ns = 1'000'000;
  int64_t total_steps = 0;   // since start (never reset): the time base of trajectories
  double physics_seconds = 0;

  // Robot layout.
  std::vector<size_t> arm_dofs;             // skeleton DoF indices, in skeleton order
  std::vector<std::string> arm_names;
  std::vector<JointLimits> arm_limits;
  std::map<std::string, size_t> arm_index;  // joint name -> index in arm_dofs
  size_t left_dof = 0, right_dof = 0;
  double finger_upper = 0.04, finger_effort = 40, finger_velocity = 0.1;
  BodyNode* tool = nullptr;

  // Controller state.
  std::vector<double> arm_target;           // held when no trajectory plays
  std::vector<double> arm_integral;         // of the position error, rad s
  JointTrajectory traj;
  int64_t traj_start_step = 0;
  std::string traj_id;
  double finger_target = 0.04;              // per finger opening
  double finger_ref = 0.04;                 // the ramp toward it
  double finger_integral = 0;               // m s, of the mean opening error
  bool finger_gripping = false;             // blocked: pushing with the force limit
  double finger_kp = 0, finger_kd = 0;      // from the finger mass and the step
  double finger_speed = kDefaultFingerSpeed / 2, finger_force = kDefaultFingerForce;
  Eigen::VectorXd applied;                  // forces applied in the last step

  void build() {
    world = simulation::World::create(scene.name);
    if (scene.physics.lcp_solver == "pgs")
      world->setConstraintSolver(std::make_unique<constraint::BoxedLcpConstraintSolver>(
          std::make_shared<constraint::PgsBoxedLcpSolver>()));
    else
      world->setConstraintSolver(std::make_unique<constraint::BoxedLcpConstraintSolver>(
          std::make_shared<constraint::DantzigBoxedLcpSolver>(), std::make_shared<constraint::PgsBoxedLcpSolver>()));
    // After the solver is set, so that it gets the step too.
    world->setTimeStep(scene.physics.step_ms * 1e-3);
    world->setGravity(Eigen::Vector3d(scene.physics.gravity[0], scene.physics.gravity[1], scene.physics.gravity[2]));
    const std::string& cd = scene.physics.collision_detector;
    if (cd == "bullet") {
      world->getConstraintSolver()->setCollisionDetector(collision::BulletCollisionDetector::create());
    } else if (cd == "dart") {
      world->getConstraintSolver()->setCollisionDetector(collision::DARTCollisionDetector::create());
    } else {
      auto fcl = collision::FCLCollisionDetector::create();
      fcl->setPrimitiveShapeType(collision::FCLCollisionDetector::PRIMITIVE);
      world->getConstraintSolver()->setCollisionDetector(fcl);
    }
    all.clear();
    objects.clear();
    std::set<const BodyNode*> fixed;

    SkeletonPtr floor = dynamics::Skeleton::create("floor");
    BodyNode* fb = floor->createJointAndBodyNodePair<dynamics::WeldJoint>().second;
    auto fs = std::make_shared<dynamics::BoxShape>(Eigen::Vector3d(4, 4, 0.1));
    fb->createShapeNodeWith<dynamics::CollisionAspect, dynamics::DynamicsAspect>(fs);
    Eigen::Isometry3d fT = Eigen::Isometry3d::Identity();
    fT.translation().z() = -0.05;
    fb->getParentJoint()->setTransformFromParentBodyNode(fT);
    set_friction(floor, 0.8);
    floor->setMobile(false);
    fixed.insert(fb);
    all.push_back(floor);

    for (const auto& f : scene.fixtures) {
      SkeletonPtr s = load_urdf(f.urdf, f.name, f.pose);
      s->setMobile(false);
      set_friction(s, f.friction);
      for (size_t b = 0; b < s->getNumBodyNodes(); ++b) fixed.insert(s->getBodyNode(b));
      all.push_back(s);
    }

    robot = load_urdf(scene.robot.urdf, scene.robot.name, scene.robot.pose);
    set_friction(robot, kRobotFriction);
    fixed.insert(robot->getRootBodyNode());
    setup_robot();
    all.push_back(robot);

    for (const auto& o : scene.objects) {
      SkeletonPtr s = dynamics::Skeleton::create(o.name);
      BodyNode* bn = s->createJointAndBodyNodePair<dynamics::FreeJoint>().second;
      bn->setName(o.name);
      dynamics::ShapePtr shape;
      if (o.shape == "box")
        shape = std::make_shared<dynamics::BoxShape>(Eigen::Vector3d(o.size[0], o.size[1], o.size[2]));
      else
        shape = std::make_shared<dynamics::CylinderShape>(o.size[0], o.size[1]);
      bn->createShapeNodeWith<dynamics::CollisionAspect, dynamics::DynamicsAspect>(shape);
      dynamics::Inertia inertia;
      inertia.setMass(o.mass);
      inertia.setMoment(shape->computeInertia(o.mass));
      bn->setInertia(inertia);
      set_friction(s, o.friction);
      s->setPositions(dynamics::FreeJoint::convertToPositions(to_iso(o.pose)));
      objects.push_back(s);
      all.push_back(s);
    }
    for (auto& s : all) world->addSkeleton(s);
    world->getConstraintSolver()->getCollisionOption().collisionFilter = std::make_shared<StaticPairFilter>(fixed);
    world->getConstraintSolver()->getCollisionOption().maxNumContacts = 200;
    applied = Eigen::VectorXd::Zero(robot->getNumDofs());
  }

  void setup_robot() {
    const RobotSpec& r = scene.robot;
    auto* lj = robot->getJoint(r.left_finger_joint);
    auto* rj = robot->getJoint(r.right_finger_joint);
    if (!lj || lj->getNumDofs() != 1) throw SceneError(scene.path + ": robot.left_finger_joint '" + r.left_finger_joint + "' is not a 1-DoF joint of " + r.urdf);
    if (!rj || rj->getNumDofs() != 1) throw SceneError(scene.path + ": robot.right_finger_joint '" + r.right_finger_joint + "' is not a 1-DoF joint of " + r.urdf);
    tool = robot->getBodyNode(r.tool_link);
    if (!tool) throw SceneError(scene.path + ": robot.tool_link '" + r.tool_link + "' is not a link of " + r.urdf);
    left_dof = lj->getDof(0)->getIndexInSkeleton();
    right_dof = rj->getDof(0)->getIndexInSkeleton();
    finger_upper = std::min(lj->getPositionUpperLimit(0), rj->getPositionUpperLimit(0));
    finger_effort = std::min(lj->getForceUpperLimit(0), rj->getForceUpperLimit(0));
    finger_velocity = std::min(lj->getVelocityUpperLimit(0), rj->getVelocityUpperLimit(0));

    arm_dofs.clear();
    arm_names.clear();
    arm_limits.clear();
    arm_index.clear();
    for (size_t i = 0; i < robot->getNumDofs(); ++i) {
      auto* dof = robot->getDof(i);
      dof->getJoint()->setLimitEnforcement(true);
      if (i == left_dof || i == right_dof) continue;
      arm_index[dof->getJoint()->getName()] = arm_dofs.size();
      arm_dofs.push_back(i);
      arm_names.push_back(dof->getJoint()->getName());
      arm_limits.push_back({dof->getPositionLowerLimit(), dof->getPositionUpperLimit(), dof->getVelocityUpperLimit()});
    }
    for (const auto& [name, q] : r.initial_joints) {
      auto* j = robot->getJoint(name);
      if (!j || j->getNumDofs() != 1) throw SceneError(scene.path + ": robot.initial_joints names '" + name + "', not a 1-DoF joint of " + r.urdf);
      if (q < j->getPositionLowerLimit(0) || q > j->getPositionUpperLimit(0))
        throw SceneError(scene.path + ": robot.initial_joints." + name + " is outside the joint's limits");
      j->setPosition(0, q);
    }
    for (const auto* sn : robot->getJoint(r.left_finger_joint)->getChildBodyNode()->getShapeNodesWith<dynamics::DynamicsAspect>())
      const_cast<dynamics::ShapeNode*>(sn)->getDynamicsAspect()->setFrictionCoeff(kFingerFriction);
    for (const auto* sn : robot->getJoint(r.right_finger_joint)->getChildBodyNode()->getShapeNodesWith<dynamics::DynamicsAspect>())
      const_cast<dynamics::ShapeNode*>(sn)->getDynamicsAspect()->setFrictionCoeff(kFingerFriction);

    arm_target.clear();
    for (size_t d : arm_dofs) arm_target.push_back(robot->getPosition(d));
    arm_integral.assign(arm_dofs.size(), 0.0);
    traj = JointTrajectory();
    traj_id.clear();
    finger_target = finger_ref = 0.5 * (robot->getPosition(left_dof) + robot->getPosition(right_dof));
    finger_integral = 0;
    finger_gripping = false;
    const double finger_mass = robot->getMassMatrix()(left_dof, left_dof);
    const double w = std::min(kFingerMaxW, kFingerMaxWdt / (step_ns * 1e-9));
    finger_kp = finger_mass * w * w;
    finger_kd = 2 * finger_mass * w;
    finger_speed = kDefaultFingerSpeed / 2;
    finger_force = std::min(kDefaultFingerForce, finger_effort);
  }

  int64_t traj_time_ns() const { return (total_steps - traj_start_step) * step_ns; }

  void control() {
    const Eigen::VectorXd q = robot->getPositions();
    const Eigen::VectorXd dq = robot->getVelocities();
    Eigen::VectorXd acc = Eigen::VectorXd::Zero(robot->getNumDofs());
    std::vector<double> qd(arm_dofs.size(), 0.0), qdd(arm_dofs.size(), 0.0), qt = arm_target;
    if (!traj.empty()) {
      const Sample s = traj.sample(traj_time_ns());
      qt = s.q;
      qd = s.qd;
      qdd = s.qdd;
    }
    const double dt = step_ns * 1e-9;
    for (size_t k = 0; k < arm_dofs.size(); ++k) {
      const size_t i = arm_dofs[k];
      const double e = qt[k] - q[i];
      arm_integral[k] = std::clamp(arm_integral[k] + e * dt, -kArmIntegralLimit, kArmIntegralLimit);
      acc[i] = qdd[k] + kArmKp * e + kArmKd * (qd[k] - dq[i]) + kArmKi * arm_integral[k];
    }
    // tau = M(q) acc + C(q, dq) + g(q) by recursive Newton-Euler: O(n), where forming M
    // costs O(n^2) every step. The accelerations set here are overwritten by the step.
    robot->setAccelerations(acc);
    robot->computeInverseDynamics(false, false, false);
    const Eigen::VectorXd tau = robot->getForces();
    for (size_t k = 0; k < arm_dofs.size(); ++k) {
      const size_t i = arm_dofs[k];
      auto* dof = robot->getDof(i);
      const double t = tau[i] + dof->getDampingCoefficient() * dq[i];
      applied[i] = std::clamp(t, dof->getForceLowerLimit(), dof->getForceUpperLimit());
    }
    // Fingers, coupled like a real parallel gripper's: their mean opening follows a
    // reference that ramps to the target at the commanded speed, under a PID whose force
    // is limited to the commanded force limit (a finger blocked by an object ends up
    // squeezing with exactly that limit, whatever the gains); their difference is held at
    // zero by a stiff PD, so a squeezed object cannot drift along the finger axis.
    const double delta = finger_target - finger_ref;
    const double max_step = finger_speed * dt;
    finger_ref += std::clamp(delta, -max_step, max_step);
    const double ref_vel = std::abs(delta) > max_step ? (delta > 0 ? finger_speed : -finger_speed) : 0.0;
    const double mean = 0.5 * (q[left_dof] + q[right_dof]), mean_vel = 0.5 * (dq[left_dof] + dq[right_dof]);
    const double diff = 0.5 * (q[left_dof] - q[right_dof]), diff_vel = 0.5 * (dq[left_dof] - dq[right_dof]);
    const double e = finger_ref - mean;
    const double ki = finger_kp * kFingerIntegralRate;
    finger_integral = std::clamp(finger_integral + e * dt, -finger_force / ki, finger_force / ki);
    // Grip mode, as a gripper's firmware does it: fingers that stop short of where they
    // should be (1 mm behind the reference and still) are blocked by something, and push
    // with the force limit itself at once, instead of letting the position loop wind up
    // to it. They leave grip mode when they move again or get a new command.
    if (!finger_gripping && std::abs(e) > kGripLag && std::abs(mean_vel) < kGripStill) finger_gripping = true;
    if (finger_gripping && (std::abs(mean_vel) > 4 * kGripStill || std::abs(e) < kGripLag / 2)) finger_gripping = false;
    const double squeeze =
        finger_gripping ? (e > 0 ? finger_force : -finger_force)
                        : std::clamp(finger_kp * e + finger_kd * (ref_vel - mean_vel) + ki * finger_integral,
                                     -finger_force, finger_force);
    const double centring = -finger_kp * diff - finger_kd * diff_vel;
    for (size_t i : {left_dof, right_dof}) {
      auto* dof = robot->getDof(i);
      const double f = squeeze + (i == left_dof ? centring : -centring) + tau[i] + dof->getDampingCoefficient() * dq[i];
      applied[i] = std::clamp(f, dof->getForceLowerLimit(), dof->getForceUpperLimit());
    }
    robot->setForces(applied);
  }

  void step() {
    control();
    const auto t0 = std::chrono::steady_clock::now();
    world->step();
    physics_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ++total_steps;
    if (!traj.empty() && traj_time_ns() >= traj.duration_ns()) {
      arm_target = traj.final_positions();
      traj = JointTrajectory();
    }
  }
};

Physics::Physics(const Scene& scene) : impl_(std::make_unique<Impl>()) {
  impl_->scene = scene;
  impl_->step_ns = static_cast<int64_t>(std::llround(scene.physics.step_ms * 1e6));
  impl_->steps_per_frame = static_cast<int>(std::llround(scene.physics.frame_ms / scene.physics.step_ms));
  impl_->build();
}

Physics::~Physics() = default;

void Physics::reset() { impl_->build(); }

std::string Physics::command_arm(const ArmCommand& cmd) {
  Impl& m = *impl_;
  if (cmd.joints.empty()) return "the command names no joints";
  if (cmd.points.empty()) return "the command has no points";
  if (cmd.points.size() > 100000) return "the command has more than 100000 points";
  std::vector<size_t> idx;
  std::set<std::string> seen;
  for (const auto& j : cmd.joints) {
    auto it = m.arm_index.find(j);
    if (it == m.arm_index.end()) {
      std::string known;
      for (const auto& n : m.arm_names) known += (known.empty() ? "" : ", ") + n;
      return "unknown arm joint '" + j + "' (the arm has " + known + ")";
    }
    if (!seen.insert(j).second) return "joint '" + j + "' is named twice";
    idx.push_back(it->second);
  }
  // Expand to all arm joints: unnamed joints keep their current target.
  const std::vector<double> start = m.traj.empty() ? m.arm_target : m.traj.sample(m.traj_time_ns()).q;
  std::vector<Waypoint> pts;
  for (size_t k = 0; k < cmd.points.size(); ++k) {
    const Waypoint& p = cmd.points[k];
    if (p.q.size() != idx.size())
      return "point " + std::to_string(k) + " has " + std::to_string(p.q.size()) + " positions for " +
             std::to_string(idx.size()) + " joints";
    if (!p.qd.empty() && p.qd.size() != idx.size())
      return "point " + std::to_string(k) + " has " + std::to_string(p.qd.size()) + " velocities for " +
             std::to_string(idx.size()) + " joints";
    Waypoint w;
    w.t_ns = p.t_ns;
    w.q = start;
    if (!p.qd.empty()) w.qd.assign(start.size(), 0.0);
    for (size_t j = 0; j < idx.size(); ++j) {
      w.q[idx[j]] = p.q[j];
      if (!p.qd.empty()) w.qd[idx[j]] = p.qd[j];
    }
    pts.push_back(std::move(w));
  }
  try {
    m.traj = JointTrajectory(start, std::move(pts), m.arm_limits, m.arm_names);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  m.traj_start_step = m.total_steps;
  m.traj_id = cmd.id;
  return "";
}

std::string Physics::command_gripper(const GripperCommand& cmd) {
  Impl& m = *impl_;
  auto bad = [](double v) { return !std::isfinite(v); };
  if (bad(cmd.width) || bad(cmd.speed) || bad(cmd.force_limit)) return "width, speed and force_limit must be finite numbers";
  const double max_width = 2 * m.finger_upper;
  if (cmd.width < 0 || cmd.width > max_width + 1e-9)
    return "width " + std::to_string(cmd.width) + " m is outside [0, " + std::to_string(max_width) + "]";
  if (cmd.speed <= 0 || cmd.speed > 2 * m.finger_velocity + 1e-9)
    return "speed " + std::to_string(cmd.speed) + " m/s is outside (0, " + std::to_string(2 * m.finger_velocity) + "]";
  if (cmd.force_limit <= 0 || cmd.force_limit > m.finger_effort + 1e-9)
    return "force_limit " + std::to_string(cmd.force_limit) + " N is outside (0, " + std::to_string(m.finger_effort) + "]";
  m.finger_target = cmd.width / 2;
  m.finger_speed = cmd.speed / 2;
  m.finger_force = cmd.force_limit;
  m.finger_integral = 0;  // a new command starts without the last one's wind-up
  m.finger_gripping = false;
  // ... and from where the fingers are: after a grip the reference has run on to the
  // closed position, and an opening must not first wait for it to come back.
  m.finger_ref = 0.5 * (m.robot->getPosition(m.left_dof) + m.robot->getPosition(m.right_dof));
  return "";
}

void Physics::step_frame() {
  for (int i = 0; i < impl_->steps_per_frame; ++i) impl_->step();
}

void Physics::fill_state(skillbus_msgs::sim_state_t& out) const {
  const Impl& m = *impl_;
  const auto& r = m.robot;
  const size_t n = r->getNumDofs();
  out.num_joints = static_cast<int32_t>(n);
  out.joint_names.resize(n);
  out.position.resize(n);
  out.velocity.resize(n);
  out.effort.resize(n);
  for (size_t i = 0; i < n; ++i) {
    out.joint_names[i] = r->getDof(i)->getJoint()->getName();
    out.position[i] = r->getPosition(i);
    out.velocity[i] = r->getVelocity(i);
    out.effort[i] = m.applied[i];
  }
  Eigen::Isometry3d tcp = m.tool->getWorldTransform();
  tcp.translate(Eigen::Vector3d(0, 0, m.scene.robot.tool_offset));
  from_iso(tcp, out.tool_pose);
  out.finger_width = r->getPosition(m.left_dof) + r->getPosition(m.right_dof);
  out.finger_force = -0.5 * (m.applied[m.left_dof] + m.applied[m.right_dof]);
  out.finger_width_target = 2 * m.finger_target;
  out.arm_command_id = m.traj_id;
  out.arm_moving = !m.traj.empty();
  std::vector<double> want = m.traj.empty() ? m.arm_target : m.traj.sample(m.traj_time_ns()).q;
  double err = 0;
  for (size_t k = 0; k < m.arm_dofs.size(); ++k) err = std::max(err, std::abs(want[k] - r->getPosition(m.arm_dofs[k])));
  out.arm_tracking_error = err;

  out.num_objects = static_cast<int32_t>(m.objects.size());
  out.objects.resize(m.objects.size());
  for (size_t k = 0; k < m.objects.size(); ++k) {
    const BodyNode* bn = m.objects[k]->getRootBodyNode();
    auto& o = out.objects[k];
    o.name = m.objects[k]->getName();
    from_iso(bn->getWorldTransform(), o.pose);
    const Eigen::Vector3d v = bn->getLinearVelocity(), w = bn->getAngularVelocity();
    for (int i = 0; i < 3; ++i) {
      o.twist[i] = v[i];
      o.twist[3 + i] = w[i];
    }
  }
  // Finger-object contacts of the last step, summed per pair in a fixed order.
  const BodyNode* fingers[2] = {r->getJoint(m.scene.robot.left_finger_joint)->getChildBodyNode(),
                                r->getJoint(m.scene.robot.right_finger_joint)->getChildBodyNode()};
  std::map<std::pair<std::string, std::string>, std::pair<int, double>> pairs;
  for (const auto& c : m.world->getLastCollisionResult().getContacts()) {
    const BodyNode* a = c.collisionObject1->getShapeFrame()->asShapeNode()->getBodyNodePtr().get();
    const BodyNode* b = c.collisionObject2->getShapeFrame()->asShapeNode()->getBodyNodePtr().get();
    if (a == fingers[0] || a == fingers[1]) {
    } else if (b == fingers[0] || b == fingers[1]) {
      std::swap(a, b);
    } else {
      continue;
    }
    if (b->getSkeleton() == r) continue;
    auto& e = pairs[{a->getName(), b->getSkeleton()->getName()}];
    e.first += 1;
    e.second += std::abs(c.force.dot(c.normal));
  }
  out.contacts.clear();
  for (const auto& [k, v] : pairs) {
    skillbus_msgs::sim_contact_t c;
    c.body_a = k.first;
    c.body_b = k.second;
    c.points = v.first;
    c.normal_force = v.second;
    out.contacts.push_back(c);
  }
  out.num_contacts = static_cast<int32_t>(out.contacts.size());
}

Digest Physics::digest() const {
  Sha256 h;
  for (const auto& s : impl_->all) {
    h.update_str(s->getName());
    const Eigen::VectorXd q = s->getPositions(), v = s->getVelocities();
    h.update(q.data(), sizeof(double) * static_cast<size_t>(q.size()));
    h.update(v.data(), sizeof(double) * static_cast<size_t>(v.size()));
  }
  return h.finish();
}

const Scene& Physics::scene() const { return impl_->scene; }
int Physics::steps_per_frame() const { return impl_->steps_per_frame; }
int64_t Physics::step_count() const { return impl_->total_steps; }
std::string Physics::collision_detector() const { return impl_->scene.physics.collision_detector; }
double Physics::physics_seconds() const { return impl_->physics_seconds; }

}  // namespace skillbus::sim
