#include "world.hpp"

#include <algorithm>
#include <dart/collision/CollisionFilter.hpp>
#include <dart/collision/CollisionObject.hpp>
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
#include <dart/dynamics/PrismaticJoint.hpp>
#include <dart/dynamics/RevoluteJoint.hpp>
#include <dart/dynamics/ShapeNode.hpp>
#include <dart/dynamics/Skeleton.hpp>
#include <dart/dynamics/WeldJoint.hpp>
#include <dart/simulation/World.hpp>
#include <dart/utils/urdf/DartLoader.hpp>
#include <set>
#include <unordered_map>
#include <vector>

namespace skillbus::sim {

using namespace dart;
using dynamics::BodyNode;
using dynamics::SkeletonPtr;
using scene::Pose;
using scene::SceneError;

namespace {

constexpr double kRobotFriction = 0.5, kFingerFriction = 1.0;

void set_friction(const SkeletonPtr& skel, double mu) {
  for (size_t b = 0; b < skel->getNumBodyNodes(); ++b)
    for (auto* sn : skel->getBodyNode(b)->getShapeNodesWith<dynamics::DynamicsAspect>())
      sn->getDynamicsAspect()->setFrictionCoeff(mu);
}

// Fixed fixtures never touch each other or the floor in a way that matters, and the
// robot's pedestal stands on the floor: skip those pairs before narrow phase.
// Ignores a pair in one skeleton that does not check self-collision, and a pair of fixed
// bodies. Asked for every overlapping pair of every step: the body and skeleton of each
// shape are looked up in a table made once (DART's getBodyNodePtr() and getSkeleton()
// count references under a lock: 6 % of a demo step), and only a shape the table does
// not have takes that way. The answers are the same either way.
class StaticPairFilter : public collision::CollisionFilter {
 public:
  StaticPairFilter(std::set<const BodyNode*> fixed, const std::vector<SkeletonPtr>& skeletons)
      : fixed_(std::move(fixed)) {
    for (const auto& s : skeletons)
      for (size_t b = 0; b < s->getNumBodyNodes(); ++b) {
        const BodyNode* bn = s->getBodyNode(b);
        for (const auto* sn : bn->getShapeNodes()) shapes_[sn] = Body{s.get(), fixed_.count(bn) > 0};
      }
  }
  bool ignoresCollision(const collision::CollisionObject* a, const collision::CollisionObject* b) const override {
    const Body ba = body_of(a), bb = body_of(b);
    if (ba.skeleton == bb.skeleton && !ba.skeleton->isEnabledSelfCollisionCheck()) return true;
    return ba.fixed && bb.fixed;
  }

 private:
  struct Body {
    const dynamics::Skeleton* skeleton = nullptr;
    bool fixed = false;
  };
  Body body_of(const collision::CollisionObject* o) const {
    const dynamics::ShapeFrame* frame = o->getShapeFrame();
    if (auto it = shapes_.find(frame); it != shapes_.end()) return it->second;
    const BodyNode* bn = frame->asShapeNode()->getBodyNodePtr().get();
    return Body{bn->getSkeleton().get(), fixed_.count(bn) > 0};
  }
  std::set<const BodyNode*> fixed_;
  // (the skeletons are the world's for its whole life, and so is this filter)
  std::unordered_map<const dynamics::ShapeFrame*, Body> shapes_;
};

SkeletonPtr load_urdf(const std::string& path, const std::string& name, const Pose& pose) {
  utils::DartLoader loader;
  SkeletonPtr skel = loader.parseSkeleton(common::Uri::createFromPath(path), nullptr, utils::DartLoader::FIXED_BASE_LINK);
  if (!skel) throw SceneError(path + ": DART cannot load this URDF (see the log above)");
  skel->setName(name);
  skel->getRootJoint()->setTransformFromParentBodyNode(to_iso(pose));
  return skel;
}

// An articulated object: its URDF fixed by its root link at the scene's pose, its joints
// passive (no controller) within their limits, with the scene's damping and Coulomb
// friction where it gives them (else the URDF's <dynamics>).
SkeletonPtr load_articulated(const scene::Scene& scene, size_t index) {
  const scene::ArticulatedSpec& a = scene.articulated[index];
  const std::string field = "articulated[" + std::to_string(index) + "]";
  SkeletonPtr s = load_urdf(a.urdf, a.name, a.pose);
  set_friction(s, a.friction);
  for (size_t j = 0; j < s->getNumJoints(); ++j) s->getJoint(j)->setLimitEnforcement(true);
  auto one_dof = [&](const std::string& name, const std::string& what) {
    dynamics::Joint* j = s->getJoint(name);
    if (!j || j->getNumDofs() != 1 ||
        (j->getType() != dynamics::PrismaticJoint::getStaticType() && j->getType() != dynamics::RevoluteJoint::getStaticType()))
      throw SceneError(scene.path + ": " + field + "." + what + " names '" + name +
                       "', not a 1-DoF prismatic or revolute joint of " + a.urdf);
    return j;
  };
  for (const auto& [name, spec] : a.joints) {
    dynamics::DegreeOfFreedom* dof = one_dof(name, "joints")->getDof(0);
    if (spec.damping) dof->setDampingCoefficient(*spec.damping);
    if (spec.friction) dof->setCoulombFriction(*spec.friction);
  }
  for (const auto& [name, q] : a.initial_joints) {
    dynamics::Joint* j = one_dof(name, "initial_joints");
    if (q < j->getPositionLowerLimit(0) || q > j->getPositionUpperLimit(0))
      throw SceneError(scene.path + ": " + field + ".initial_joints." + name + " is outside the joint's limits");
    j->setPosition(0, q);
  }
  return s;
}

}  // namespace

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

World build_world(const scene::Scene& scene,
                  const std::function<void(size_t index, dynamics::Skeleton& robot)>& set_up_robot) {
  World w;
  auto& world = w.sim;
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
  auto& all = w.all;
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

  for (size_t i = 0; i < scene.robots.size(); ++i) {
    const scene::RobotSpec& spec = scene.robots[i];
    SkeletonPtr robot = load_urdf(spec.urdf, spec.name, spec.pose);
    w.robots.push_back(robot);
    set_friction(robot, kRobotFriction);
    fixed.insert(robot->getRootBodyNode());
    set_up_robot(i, *robot);
    all.push_back(robot);
  }

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
    w.objects.push_back(s);
    all.push_back(s);
  }
  // Articulated objects move: only their root link is fixed (it never meets the floor or
  // a fixture); their moving links meet the robots and the objects. Self-collision stays
  // off (a drawer slides inside its body).
  for (size_t i = 0; i < scene.articulated.size(); ++i) {
    SkeletonPtr s = load_articulated(scene, i);
    fixed.insert(s->getRootBodyNode());
    w.articulated.push_back(s);
    all.push_back(s);
  }
  for (auto& s : all) world->addSkeleton(s);
  world->getConstraintSolver()->getCollisionOption().collisionFilter = std::make_shared<StaticPairFilter>(fixed, all);
  world->getConstraintSolver()->getCollisionOption().maxNumContacts = 200;
  return w;
}

RobotLayout set_up_robot(dynamics::Skeleton& robot, const scene::Scene& scene, const scene::RobotSpec& r) {
  // Errors name the robot's field as the scene file does: robot.X, or robots[i].X.
  std::string field = "robot";
  if (!r.bus_name.empty())
    for (size_t i = 0; i < scene.robots.size(); ++i)
      if (&scene.robots[i] == &r) field = "robots[" + std::to_string(i) + "]";
  RobotLayout out;
  auto* lj = robot.getJoint(r.left_finger_joint);
  auto* rj = robot.getJoint(r.right_finger_joint);
  if (!lj || lj->getNumDofs() != 1) throw SceneError(scene.path + ": " + field + ".left_finger_joint '" + r.left_finger_joint + "' is not a 1-DoF joint of " + r.urdf);
  if (!rj || rj->getNumDofs() != 1) throw SceneError(scene.path + ": " + field + ".right_finger_joint '" + r.right_finger_joint + "' is not a 1-DoF joint of " + r.urdf);
  out.tool = robot.getBodyNode(r.tool_link);
  if (!out.tool) throw SceneError(scene.path + ": " + field + ".tool_link '" + r.tool_link + "' is not a link of " + r.urdf);
  out.left_dof = lj->getDof(0)->getIndexInSkeleton();
  out.right_dof = rj->getDof(0)->getIndexInSkeleton();
  out.finger_limits.upper = std::min(lj->getPositionUpperLimit(0), rj->getPositionUpperLimit(0));
  out.finger_limits.effort = std::min(lj->getForceUpperLimit(0), rj->getForceUpperLimit(0));
  out.finger_limits.velocity = std::min(lj->getVelocityUpperLimit(0), rj->getVelocityUpperLimit(0));

  for (size_t i = 0; i < robot.getNumDofs(); ++i) {
    auto* dof = robot.getDof(i);
    dof->getJoint()->setLimitEnforcement(true);
    if (i == out.left_dof || i == out.right_dof) continue;
    out.arm_dofs.push_back(i);
    out.arm_names.push_back(dof->getJoint()->getName());
    out.arm_limits.push_back({dof->getPositionLowerLimit(), dof->getPositionUpperLimit(), dof->getVelocityUpperLimit()});
  }
  for (const auto& [name, q] : r.initial_joints) {
    auto* j = robot.getJoint(name);
    if (!j || j->getNumDofs() != 1) throw SceneError(scene.path + ": " + field + ".initial_joints names '" + name + "', not a 1-DoF joint of " + r.urdf);
    if (q < j->getPositionLowerLimit(0) || q > j->getPositionUpperLimit(0))
      throw SceneError(scene.path + ": " + field + ".initial_joints." + name + " is outside the joint's limits");
    j->setPosition(0, q);
  }
  for (const auto* sn : robot.getJoint(r.left_finger_joint)->getChildBodyNode()->getShapeNodesWith<dynamics::DynamicsAspect>())
    const_cast<dynamics::ShapeNode*>(sn)->getDynamicsAspect()->setFrictionCoeff(kFingerFriction);
  for (const auto* sn : robot.getJoint(r.right_finger_joint)->getChildBodyNode()->getShapeNodesWith<dynamics::DynamicsAspect>())
    const_cast<dynamics::ShapeNode*>(sn)->getDynamicsAspect()->setFrictionCoeff(kFingerFriction);
  return out;
}

}  // namespace skillbus::sim
