// The physics' outputs: the state messages every frame (the simulator's ground truth, and
// the robot's arm state and camera as a real robot's drivers report them), and the
// digest of the world.
#include <algorithm>
#include <cmath>
#include <dart/collision/CollisionObject.hpp>
#include <dart/collision/CollisionResult.hpp>
#include <dart/dynamics/BodyNode.hpp>
#include <dart/dynamics/DegreeOfFreedom.hpp>
#include <dart/dynamics/Joint.hpp>
#include <dart/dynamics/PrismaticJoint.hpp>
#include <dart/dynamics/RevoluteJoint.hpp>
#include <dart/dynamics/ShapeNode.hpp>
#include <dart/dynamics/Skeleton.hpp>
#include <dart/simulation/World.hpp>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "physics_impl.hpp"

namespace skillbus::sim {

using dart::dynamics::BodyNode;

// The tool link moved by the scene's tool offset.
void RobotRig::tool_pose(double* out) const {
  Eigen::Isometry3d tcp = layout.tool->getWorldTransform();
  tcp.translate(Eigen::Vector3d(0, 0, spec->tool_offset));
  from_iso(tcp, out);
}

double RobotRig::tracking_error(int64_t total_steps) const {
  const std::vector<double> want = arm.reference_positions(total_steps);
  double err = 0;
  for (size_t k = 0; k < layout.arm_dofs.size(); ++k)
    err = std::max(err, std::abs(want[k] - skeleton->getPosition(layout.arm_dofs[k])));
  return err;
}

namespace {

// Names, positions, velocities and applied efforts of the robot's `dofs`, in that order:
// the robot's joint state in both the robot's and the simulator's message.
template <class Robot, class Efforts, class Msg>
void fill_joints(const Robot& r, const Efforts& applied, const std::vector<size_t>& dofs, Msg& out) {
  const size_t n = dofs.size();
  out.num_joints = static_cast<int32_t>(n);
  out.joint_names.resize(n);
  out.position.resize(n);
  out.velocity.resize(n);
  out.effort.resize(n);
  for (size_t k = 0; k < n; ++k) {
    const size_t i = dofs[k];
    out.joint_names[k] = r->getDof(i)->getJoint()->getName();
    out.position[k] = r->getPosition(i);
    out.velocity[k] = r->getVelocity(i);
    out.effort[k] = applied[static_cast<Eigen::Index>(i)];
  }
}

}  // namespace

void Physics::fill_arm_state(size_t robot, skillbus_msgs::robot_arm_state_t& out) const {
  const RobotRig& r = impl_->rig(robot);
  fill_joints(r.skeleton, r.applied, r.layout.arm_dofs, out);
  r.tool_pose(out.tool_pose);
  out.arm_command_id = r.arm.command_id();
  out.arm_moving = r.arm.moving();
  out.arm_tracking_error = r.tracking_error(impl_->total_steps);
}

// What each object rests on, from the last step's contacts (a perfect camera's reading
// of the scene, as a perception pipeline would segment objects above support surfaces):
// the label of the gripper whose two fingers touch it; else the fixture it touches at the most
// contact points (ties: the first name), which names the world model's Location by its
// label; an object that touches only other objects rests on what they rest on; "" when
// it touches nothing it could rest on (falling), or only the floor (no world model label).
// Before the first step of a (re)built world: the scene's `on` of each object. An object
// attached to a robot's tool (Physics::attach) is held by that robot's gripper. An
// articulated object counts as a fixture: its body by its name, a link that one of the
// scene's joints moves (or a link below it) by the world model's label of that joint's
// part, "<object>/<joint>" (a drawer holds what lies in it).
std::vector<std::string> Physics::Impl::supports() const {
  std::vector<std::string> out = contact_supports();
  for (const Attachment& a : attachments) out[a.object] = robots[a.robot].spec->gripper;
  return out;
}

namespace {

// The world-model label of what an articulated object's body node is: "<object>/<joint>"
// for the child link of a joint the scene lists (or any link below one), else the
// object's name.
std::string articulated_label(const scene::ArticulatedSpec& spec, const BodyNode* bn) {
  for (const BodyNode* b = bn; b; b = b->getParentBodyNode()) {
    const auto* j = b->getParentJoint();
    if (j && spec.joints.count(j->getName())) return spec.name + "/" + j->getName();
  }
  return spec.name;
}

}  // namespace

std::vector<std::string> Physics::Impl::contact_supports() const {
  const auto& objects = world.objects;
  // Each robot's two fingers, and the labels of the grippers.
  std::map<const BodyNode*, std::pair<size_t, int>> fingers;  // finger -> (robot, bit)
  std::set<std::string> grippers;
  for (size_t i = 0; i < robots.size(); ++i) {
    const RobotRig& r = robots[i];
    fingers[r.skeleton->getJoint(r.spec->left_finger_joint)->getChildBodyNode()] = {i, 1};
    fingers[r.skeleton->getJoint(r.spec->right_finger_joint)->getChildBodyNode()] = {i, 2};
    grippers.insert(r.spec->gripper);
  }
  std::map<const dart::dynamics::Skeleton*, size_t> index;
  for (size_t k = 0; k < objects.size(); ++k) index[objects[k].get()] = k;
  std::set<std::string> fixtures;
  for (const auto& f : scene.fixtures) fixtures.insert(f.name);
  std::map<const dart::dynamics::Skeleton*, const scene::ArticulatedSpec*> articulated;
  for (size_t i = 0; i < world.articulated.size(); ++i) articulated[world.articulated[i].get()] = &scene.articulated[i];
  if (steps_since_build == 0) {  // no step, no contacts yet: what the scene says each starts on
    std::vector<std::string> out;
    for (const auto& o : scene.objects) out.push_back(o.on);
    return out;
  }
  std::vector<std::map<size_t, int>> finger_bits(objects.size());  // per object: robot -> fingers touching
  std::vector<std::map<std::string, int>> fixture_points(objects.size());
  std::vector<std::set<size_t>> touching(objects.size());
  auto body = [](const dart::collision::CollisionObject* o) {
    return o->getShapeFrame()->asShapeNode()->getBodyNodePtr().get();
  };
  auto note = [&](const BodyNode* object, const BodyNode* other) {
    const auto it = index.find(object->getSkeleton().get());
    if (it == index.end()) return;
    const size_t k = it->second;
    if (const auto f = fingers.find(other); f != fingers.end()) finger_bits[k][f->second.first] |= f->second.second;
    else if (const auto o = index.find(other->getSkeleton().get()); o != index.end()) touching[k].insert(o->second);
    else if (fixtures.count(other->getSkeleton()->getName())) fixture_points[k][other->getSkeleton()->getName()] += 1;
    else if (const auto a = articulated.find(other->getSkeleton().get()); a != articulated.end())
      fixture_points[k][articulated_label(*a->second, other)] += 1;
  };
  for (const auto& c : world.sim->getLastCollisionResult().getContacts()) {
    const BodyNode* a = body(c.collisionObject1);
    const BodyNode* b = body(c.collisionObject2);
    note(a, b);
    note(b, a);
  }
  std::vector<std::string> out(objects.size());
  for (size_t k = 0; k < objects.size(); ++k) {
    const auto held = std::find_if(finger_bits[k].begin(), finger_bits[k].end(), [](const auto& b) { return b.second == 3; });
    if (held != finger_bits[k].end()) {  // (two grippers holding one object: the first robot's)
      out[k] = robots[held->first].spec->gripper;
      continue;
    }
    int best = 0;
    for (const auto& [name, points] : fixture_points[k])
      if (points > best) best = points, out[k] = name;
  }
  // Stacks: an object on objects rests where they rest (a few passes reach a stack's top).
  for (int pass = 0; pass < 3; ++pass)
    for (size_t k = 0; k < objects.size(); ++k)
      if (out[k].empty() && finger_bits[k].empty())
        for (size_t o : touching[k])
          if (!out[o].empty() && !grippers.count(out[o])) {
            out[k] = out[o];
            break;
          }
  return out;
}

void Physics::fill_objects(skillbus_msgs::robot_objects_t& out) const {
  const auto& objects = impl_->world.objects;
  const std::vector<std::string> support = impl_->supports();
  out.num_objects = static_cast<int32_t>(objects.size());
  out.objects.resize(objects.size());
  for (size_t k = 0; k < objects.size(); ++k) {
    out.objects[k].name = objects[k]->getName();
    from_iso(objects[k]->getRootBodyNode()->getWorldTransform(), out.objects[k].pose);
    out.objects[k].support = support[k];
  }
}

void Physics::fill_articulation(size_t robot, skillbus_msgs::articulation_state_t& out) const {
  using dart::dynamics::PrismaticJoint;
  using dart::dynamics::RevoluteJoint;
  const Impl& m = *impl_;
  m.rig(robot);  // (every robot sees the same joints; a robot the scene has not is an error)
  out.joints.clear();
  for (size_t i = 0; i < m.scene.articulated.size(); ++i) {
    const scene::ArticulatedSpec& spec = m.scene.articulated[i];
    const dart::dynamics::Skeleton& skel = *m.world.articulated[i];
    for (const auto& [name, js] : spec.joints) {  // (a std::map: by joint name)
      const dart::dynamics::Joint* j = skel.getJoint(name);  // (world.cpp checked: 1-DoF, prismatic or revolute)
      const bool prismatic = j->getType() == PrismaticJoint::getStaticType();
      skillbus_msgs::articulated_joint_t e{};
      e.object = spec.name;
      e.joint = name;
      e.concept = js.type;
      e.kind = prismatic ? "prismatic" : "revolute";
      e.position = j->getPosition(0);
      e.velocity = j->getVelocity(0);
      e.lower = j->getPositionLowerLimit(0);
      e.upper = j->getPositionUpperLimit(0);
      // DART places the child at parent * T(parent->joint) * motion(q) * T(child->joint)^-1,
      // so the joint's frame (in which its axis is given) is child * T(child->joint). The
      // motion along or about the axis leaves the axis the same in the frames before and after it.
      const BodyNode* child = j->getChildBodyNode();
      const Eigen::Isometry3d frame = child->getWorldTransform() * j->getTransformFromChildBodyNode();
      const Eigen::Vector3d local = prismatic ? static_cast<const PrismaticJoint*>(j)->getAxis()
                                              : static_cast<const RevoluteJoint*>(j)->getAxis();
      const Eigen::Vector3d axis = (frame.linear() * local).normalized();
      for (int k = 0; k < 3; ++k) {
        e.axis[k] = axis[k];
        e.origin[k] = frame.translation()[k];
      }
      e.has_handle = js.handle.has_value();
      if (js.handle) {
        from_iso(child->getWorldTransform() * to_iso(*js.handle), e.handle_pose);
      } else {
        for (double& v : e.handle_pose) v = 0;
        e.handle_pose[6] = 1;
      }
      out.joints.push_back(std::move(e));
    }
  }
  out.num_joints = static_cast<int32_t>(out.joints.size());
}

void Physics::fill_state(size_t robot, skillbus_msgs::sim_state_t& out) const {
  const Impl& m = *impl_;
  const RobotRig& rig = m.rig(robot);
  const auto& r = rig.skeleton;
  std::vector<size_t> all(r->getNumDofs());
  for (size_t i = 0; i < all.size(); ++i) all[i] = i;
  fill_joints(r, rig.applied, all, out);
  rig.tool_pose(out.tool_pose);
  out.finger_width = r->getPosition(rig.layout.left_dof) + r->getPosition(rig.layout.right_dof);
  out.finger_force = -0.5 * (rig.applied[rig.layout.left_dof] + rig.applied[rig.layout.right_dof]);
  out.finger_width_target = 2 * rig.fingers.target();
  out.arm_command_id = rig.arm.command_id();
  out.arm_moving = rig.arm.moving();
  out.arm_tracking_error = rig.tracking_error(m.total_steps);

  const auto& objects = m.world.objects;
  out.num_objects = static_cast<int32_t>(objects.size());
  out.objects.resize(objects.size());
  for (size_t k = 0; k < objects.size(); ++k) {
    const BodyNode* bn = objects[k]->getRootBodyNode();
    auto& o = out.objects[k];
    o.name = objects[k]->getName();
    from_iso(bn->getWorldTransform(), o.pose);
    const Eigen::Vector3d v = bn->getLinearVelocity(), w = bn->getAngularVelocity();
    for (int i = 0; i < 3; ++i) {
      o.twist[i] = v[i];
      o.twist[3 + i] = w[i];
    }
  }
  // Finger-object contacts of the last step, summed per pair in a fixed order.
  const BodyNode* fingers[2] = {r->getJoint(rig.spec->left_finger_joint)->getChildBodyNode(),
                                r->getJoint(rig.spec->right_finger_joint)->getChildBodyNode()};
  std::map<std::pair<std::string, std::string>, std::pair<int, double>> pairs;
  for (const auto& c : m.world.sim->getLastCollisionResult().getContacts()) {
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
  for (const auto& s : impl_->world.all) {
    h.update_str(s->getName());
    const Eigen::VectorXd q = s->getPositions(), v = s->getVelocities();
    h.update(q.data(), sizeof(double) * static_cast<size_t>(q.size()));
    h.update(v.data(), sizeof(double) * static_cast<size_t>(v.size()));
  }
  return h.finish();
}

}  // namespace skillbus::sim
