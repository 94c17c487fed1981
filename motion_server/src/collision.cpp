#include "skillbus/motion/collision.hpp"

#include <algorithm>
#include <dart/collision/CollisionFilter.hpp>
#include <dart/collision/CollisionGroup.hpp>
#include <dart/collision/CollisionObject.hpp>
#include <dart/collision/fcl/FCLCollisionDetector.hpp>
#include <dart/collision/fcl/FCLCollisionObject.hpp>
#include <dart/collision/fcl/FCLTypes.hpp>
#include <dart/dynamics/BodyNode.hpp>
#include <dart/dynamics/BoxShape.hpp>
#include <dart/dynamics/CylinderShape.hpp>
#include <dart/dynamics/DegreeOfFreedom.hpp>
#include <dart/dynamics/Joint.hpp>
#include <dart/dynamics/ShapeNode.hpp>
#include <dart/dynamics/SimpleFrame.hpp>
#include <dart/dynamics/Skeleton.hpp>
#include <dart/dynamics/SphereShape.hpp>
#include <dart/dynamics/VoxelGridShape.hpp>
#include <dart/utils/urdf/DartLoader.hpp>
#include <map>
#include <set>

namespace skillbus::motion {

using namespace dart;

namespace {

constexpr const char* kHeld = "held object";
constexpr const char* kMap = "the occupancy map";

dynamics::SkeletonPtr load(const std::string& urdf, const std::string& name, const scene::Pose& pose,
                           const std::string& scene_path) {
  utils::DartLoader loader;
  dynamics::SkeletonPtr s =
      loader.parseSkeleton(common::Uri::createFromPath(urdf), nullptr, utils::DartLoader::FIXED_BASE_LINK);
  if (!s) throw scene::SceneError(scene_path + ": " + urdf + ": DART cannot load this URDF");
  s->setName(name);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(pose[0], pose[1], pose[2]);
  T.linear() = Eigen::Quaterniond(pose[6], pose[3], pose[4], pose[5]).normalized().toRotationMatrix();
  s->getRootJoint()->setTransformFromParentBodyNode(T);
  return s;
}

// An obstacle's shapes grown by `m` on every side (boxes, cylinders, spheres: what URDF
// primitives are).
void grow(const dynamics::SkeletonPtr& s, double m) {
  for (size_t b = 0; b < s->getNumBodyNodes(); ++b)
    for (auto* sn : s->getBodyNode(b)->getShapeNodes()) {
      const auto& shape = sn->getShape();
      if (auto* box = dynamic_cast<dynamics::BoxShape*>(shape.get()))
        box->setSize(box->getSize() + Eigen::Vector3d::Constant(2 * m));
      else if (auto* cyl = dynamic_cast<dynamics::CylinderShape*>(shape.get())) {
        cyl->setRadius(cyl->getRadius() + m);
        cyl->setHeight(cyl->getHeight() + 2 * m);
      } else if (auto* sphere = dynamic_cast<dynamics::SphereShape*>(shape.get()))
        sphere->setRadius(sphere->getRadius() + m);
    }
}

// Ignores the pairs a check allows (contacts the arm starts in).
class AllowedPairs : public collision::CollisionFilter {
 public:
  AllowedPairs(const std::map<const dynamics::ShapeFrame*, std::string>& names, const std::vector<Touch>& allowed)
      : names_(names) {
    for (const auto& t : allowed) allowed_.insert({t.part, t.body});
  }
  bool ignoresCollision(const collision::CollisionObject* a, const collision::CollisionObject* b) const override {
    return allows(a->getShapeFrame(), b->getShapeFrame());
  }
  // Whether the contact of these two shapes is allowed (either way round).
  bool allows(const dynamics::ShapeFrame* a, const dynamics::ShapeFrame* b) const {
    if (allowed_.empty()) return false;
    const std::string& na = names_.at(a);
    const std::string& nb = names_.at(b);
    return allowed_.count({na, nb}) > 0 || allowed_.count({nb, na}) > 0;
  }

 private:
  const std::map<const dynamics::ShapeFrame*, std::string>& names_;
  std::set<std::pair<std::string, std::string>> allowed_;
};

// DART's FCL detector, whose collision objects `clear` also holds itself: it checks the
// arm's shapes against the world's pair by pair, without the two groups' broad phase.
// DART's group against group re-sorts the arm's AABB tree at every state (removing and
// inserting each moved link's leaf) and recomputes every static shape's box: three
// quarters of a check, with a dozen shapes a side. The narrow phase is the same call DART
// makes (fcl::collide on the same geometry, with DART's request), on the same pairs less
// those whose boxes do not overlap (which DART's broad phase skips too): the same answer.
class PairDetector : public collision::FCLCollisionDetector {
 public:
  PairDetector() = default;
  std::unique_ptr<collision::CollisionObject> object_for(const dynamics::ShapeFrame* frame) {
    return createCollisionObject(frame);
  }
};

// One side of the pairwise check: a shape's own FCL object, kept at its frame's pose.
struct PairObject {
  std::unique_ptr<collision::CollisionObject> owner;
  collision::fcl::CollisionObject* fcl = nullptr;
  const dynamics::ShapeFrame* frame = nullptr;
  void place() {
    fcl->setTransform(collision::FCLTypes::convertTransform(frame->getWorldTransform()));
    fcl->computeAABB();
  }
};

}  // namespace

struct CollisionModel::Impl {
  CollisionOptions options;
  dynamics::SkeletonPtr robot;
  std::vector<size_t> dofs;
  dynamics::BodyNode* tool = nullptr;
  Eigen::Vector3d tool_offset = Eigen::Vector3d::Zero();
  std::vector<dynamics::SkeletonPtr> fixtures;
  std::set<std::string> obstacle_names;
  std::shared_ptr<dynamics::SimpleFrame> held, map;
  Eigen::Vector3d held_size = Eigen::Vector3d::Zero();  // held's box (set_held)
  std::shared_ptr<dynamics::VoxelGridShape> voxels;
  std::vector<Eigen::Vector3d> occupied;
  double resolution = 0;
  std::shared_ptr<PairDetector> detector;
  std::unique_ptr<collision::CollisionGroup> arm, world;
  // Each shape's name: the robot's link, the held object, a fixture, the map.
  std::map<const dynamics::ShapeFrame*, std::string> names;
  mutable std::shared_ptr<AllowedPairs> filter;  // clear()'s, for the contacts in filter_for
  mutable std::vector<Touch> filter_for;
  // clear()'s own objects (made again when the held object or the map changes) and which
  // arm-world pairs its allowed contacts skip (arm-major), for `filter_for`.
  mutable std::vector<PairObject> arm_objects, world_objects;
  mutable bool objects_stale = true;
  mutable std::vector<char> skipped;
  mutable bool skipped_stale = true;

  void make_objects() const {
    auto make = [&](const collision::CollisionGroup& g, std::vector<PairObject>& out) {
      out.clear();
      for (size_t i = 0; i < g.getNumShapeFrames(); ++i) {
        PairObject o;
        o.frame = g.getShapeFrame(i);
        o.owner = detector->object_for(o.frame);
        o.fcl = static_cast<collision::FCLCollisionObject*>(o.owner.get())->getFCLCollisionObject();
        out.push_back(std::move(o));
      }
    };
    make(*arm, arm_objects);
    make(*world, world_objects);
    for (auto& w : world_objects) w.place();  // (fixtures and the map never move)
    objects_stale = false;
    skipped_stale = true;
  }
  // The filter of the allowed contacts, made again only when they change (the path search
  // asks thousands of times with the same ones).
  void use_allowed(const std::vector<Touch>& allowed) const {
    if (filter && filter_for == allowed) return;
    filter = std::make_shared<AllowedPairs>(names, allowed);
    filter_for = allowed;
    skipped_stale = true;
  }
  // Which arm-world pairs the filter skips, for clear()'s own loop.
  void mark_skipped() const {
    skipped.assign(arm_objects.size() * world_objects.size(), 0);
    for (size_t a = 0; a < arm_objects.size(); ++a)
      for (size_t w = 0; w < world_objects.size(); ++w)
        skipped[a * world_objects.size() + w] = filter->allows(arm_objects[a].frame, world_objects[w].frame);
    skipped_stale = false;
  }

  void set(const Eigen::VectorXd& q) const {
    for (size_t k = 0; k < dofs.size(); ++k) robot->setPosition(dofs[k], q[static_cast<Eigen::Index>(k)]);
  }
  void rebuild_map() {
    if (map) {
      names.erase(map.get());
      world->removeShapeFrame(map.get());
      map.reset();
    }
    objects_stale = true;
    if (occupied.empty()) return;
    voxels = std::make_shared<dynamics::VoxelGridShape>(resolution);
    for (const auto& p : occupied) voxels->updateOccupancy(p, true);
    map = std::make_shared<dynamics::SimpleFrame>(dynamics::Frame::World(), "map");
    map->setShape(voxels);
    names[map.get()] = kMap;
    world->addShapeFrame(map.get());
  }
};

CollisionModel::CollisionModel(const scene::Scene& scene, const std::string& robot, CollisionOptions options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.options = options;
  const scene::RobotSpec& r = scene::robot_on_bus(scene, robot);
  m.robot = load(r.urdf, r.name, r.pose, scene.path);
  for (size_t i = 0; i < m.robot->getNumDofs(); ++i) {
    auto* dof = m.robot->getDof(i);
    const std::string joint = dof->getJoint()->getName();
    if (const auto it = r.initial_joints.find(joint); it != r.initial_joints.end()) dof->setPosition(it->second);
    if (joint != r.left_finger_joint && joint != r.right_finger_joint) m.dofs.push_back(i);
  }
  m.tool = m.robot->getBodyNode(r.tool_link);
  if (!m.tool) throw scene::SceneError(scene.path + ": robot " + r.name + ": tool_link '" + r.tool_link + "' is not a link");
  m.tool_offset = Eigen::Vector3d(0, 0, r.tool_offset);
  for (const auto& f : scene.fixtures) {
    m.fixtures.push_back(load(f.urdf, f.name, f.pose, scene.path));
    if (f.obstacle) {
      grow(m.fixtures.back(), options.obstacle_margin);
      m.obstacle_names.insert(f.name);
    }
  }
  m.detector = std::make_shared<PairDetector>();  // boxes as meshes: exact (DART's default)
  m.arm = m.detector->createCollisionGroup(m.robot.get());
  m.world = m.detector->createCollisionGroup();
  for (const auto& s : m.fixtures) m.world->addShapeFramesOf(s.get());
  for (size_t b = 0; b < m.robot->getNumBodyNodes(); ++b)
    for (auto* sn : m.robot->getBodyNode(b)->getShapeNodes()) m.names[sn] = m.robot->getBodyNode(b)->getName();
  for (const auto& s : m.fixtures)
    for (size_t b = 0; b < s->getNumBodyNodes(); ++b)
      for (auto* sn : s->getBodyNode(b)->getShapeNodes()) m.names[sn] = s->getName();
}

CollisionModel::~CollisionModel() = default;

void CollisionModel::set_held(const Eigen::Vector3d& size) {
  Impl& m = *impl_;
  // The same box again (every plan sets it): the collision objects made for it stay.
  const bool holds = size.minCoeff() > 0;
  if (holds == static_cast<bool>(m.held) && (!holds || size == m.held_size)) return;
  m.held_size = size;
  m.objects_stale = true;
  if (m.held) {
    m.names.erase(m.held.get());
    m.arm->removeShapeFrame(m.held.get());
    m.held.reset();
  }
  if (!(size.minCoeff() > 0)) return;
  Eigen::Isometry3d at = Eigen::Isometry3d::Identity();
  at.translation() = m.tool_offset;
  m.held = std::make_shared<dynamics::SimpleFrame>(m.tool, "held", at);
  m.held->setShape(std::make_shared<dynamics::BoxShape>(size));
  m.names[m.held.get()] = kHeld;
  m.arm->addShapeFrame(m.held.get());
}

void CollisionModel::set_map(const std::vector<Eigen::Vector3d>& occupied, double resolution) {
  impl_->occupied = occupied;
  impl_->resolution = resolution > 0 ? resolution : 0.01;
  impl_->rebuild_map();
}

size_t CollisionModel::map_voxels() const { return impl_->occupied.size(); }

void CollisionModel::clear_map_around(const Eigen::Vector3d& centre, double radius) {
  auto& v = impl_->occupied;
  const size_t before = v.size();
  v.erase(std::remove_if(v.begin(), v.end(), [&](const Eigen::Vector3d& p) { return (p - centre).norm() <= radius; }),
          v.end());
  if (v.size() != before) impl_->rebuild_map();
}

std::vector<Touch> CollisionModel::touches(const Eigen::VectorXd& q) const {
  const Impl& m = *impl_;
  m.set(q);
  collision::CollisionOption option(true, 1000);
  collision::CollisionResult result;
  m.arm->collide(m.world.get(), option, &result);
  std::set<std::pair<std::string, std::string>> pairs;
  for (const auto& c : result.getContacts()) {
    const std::string& a = m.names.at(c.collisionObject1->getShapeFrame());
    const std::string& b = m.names.at(c.collisionObject2->getShapeFrame());
    // Which of the two is the robot's: the arm group's objects come first in DART's
    // pairs, but ask rather than rely on it.
    const bool a_is_arm = m.arm->hasShapeFrame(c.collisionObject1->getShapeFrame());
    pairs.insert(a_is_arm ? std::make_pair(a, b) : std::make_pair(b, a));
  }
  std::vector<Touch> out;
  for (const auto& [part, body] : pairs) out.push_back({part, body, m.obstacle_names.count(body) > 0});
  return out;
}

bool CollisionModel::clear(const Eigen::VectorXd& q, const std::vector<Touch>& allowed) const {
  const Impl& m = *impl_;
  m.set(q);
  if (m.objects_stale) m.make_objects();
  m.use_allowed(allowed);
  if (m.skipped_stale) m.mark_skipped();
  for (auto& a : m.arm_objects) a.place();
  // DART's request for a yes/no check (FCLCollisionDetector: CollisionOption(false, 1)).
  collision::fcl::CollisionRequest request;
  request.num_max_contacts = 100;
  request.enable_contact = false;
  request.gjk_solver_type = ::fcl::GST_LIBCCD;
  collision::fcl::CollisionResult result;
  const size_t nw = m.world_objects.size();
  for (size_t a = 0; a < m.arm_objects.size(); ++a) {
    const auto* oa = m.arm_objects[a].fcl;
    for (size_t w = 0; w < nw; ++w) {
      if (m.skipped[a * nw + w]) continue;
      const auto* ow = m.world_objects[w].fcl;
      if (!oa->getAABB().overlap(ow->getAABB())) continue;
      result.clear();
      ::fcl::collide(oa, ow, request, result);
      if (result.isCollision()) return false;
    }
  }
  return true;
}

bool CollisionModel::clear_by_groups(const Eigen::VectorXd& q, const std::vector<Touch>& allowed) const {
  const Impl& m = *impl_;
  m.set(q);
  m.use_allowed(allowed);
  collision::CollisionOption option(false, 1);
  option.collisionFilter = m.filter;
  return !m.arm->collide(m.world.get(), option, nullptr);
}

}  // namespace skillbus::motion
