#include "skillbus/scene/turtle.hpp"

#include <array>
#include <charconv>
#include <map>

#include "skillbus/wm/rdf.hpp"

namespace skillbus::scene {

namespace {

using Quat = std::array<double, 4>;  // x y z w

// As skillbus.quat.qmul, qconj and rotate (the same order of operations, so the same bits).
Quat qmul(const Quat& a, const Quat& b) {
  const auto [ax, ay, az, aw] = a;
  const auto [bx, by, bz, bw] = b;
  return {aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
          aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz};
}
Quat qconj(const Quat& q) { return {-q[0], -q[1], -q[2], q[3]}; }
Quat rotate(const Quat& q, double x, double y, double z) { return qmul(qmul(q, {x, y, z, 0.0}), qconj(q)); }

const std::string kSkiros = "http://rvmi.aau.dk/ontologies/skiros.owl#";

// Builds the triples of one subject after another.
class Triples {
 public:
  void subject(const std::string& id) { s_ = wm::Term{wm::Term::Iri, kSkiros + id, "", ""}; }
  void type(const std::string& concept) {
    iri(wm::kRdfType, kSkiros + concept);
    iri(wm::kRdfType, wm::kOwlNamedIndividual);
  }
  void label(const std::string& text) { add(wm::kRdfsLabel, wm::Term{wm::Term::Literal, text, "", ""}); }
  void string(const std::string& property, const std::string& text) {
    add(kSkiros + property, wm::Term{wm::Term::Literal, text, std::string(wm::kXsd) + "string", ""});
  }
  void number(const std::string& property, double v) {
    add(kSkiros + property, wm::Term{wm::Term::Literal, turtle_number(v), std::string(wm::kXsd) + "float", ""});
  }
  void relation(const std::string& property, const std::string& id) { iri(kSkiros + property, kSkiros + id); }
  const std::vector<wm::Triple>& all() const { return out_; }

 private:
  void iri(const std::string& p, const std::string& o) { add(p, wm::Term{wm::Term::Iri, o, "", ""}); }
  void add(const std::string& p, wm::Term o) { out_.push_back({s_, wm::Term{wm::Term::Iri, p, "", ""}, std::move(o)}); }
  wm::Term s_;
  std::vector<wm::Triple> out_;
};

// A comment line must stay one line, whatever the scene's name holds.
std::string one_line(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s;
}

}  // namespace

Pose relative_pose(const Pose& parent, const Pose& child) {
  const Quat pq{parent[3], parent[4], parent[5], parent[6]};
  const Quat p = rotate(qconj(pq), child[0] - parent[0], child[1] - parent[1], child[2] - parent[2]);
  const Quat q = qmul(qconj(pq), {child[3], child[4], child[5], child[6]});
  return {p[0], p[1], p[2], q[0], q[1], q[2], q[3]};
}

std::string turtle_number(double v) {
  char buf[400];  // fixed notation of the largest double with 6 decimals fits
  auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, 6);
  double rounded = 0;
  std::from_chars(buf, r.ptr, rounded);
  if (rounded == 0) rounded = 0;  // -0 -> 0
  r = std::to_chars(buf, buf + sizeof buf, rounded);
  return std::string(buf, r.ptr);
}

std::vector<WorldElement> world_elements(const Scene& scene) {
  std::vector<WorldElement> out;
  auto id = [&](const std::string& type) { return type + "-" + std::to_string(out.size() + 1); };
  auto add = [&](WorldElement::Kind kind, const std::string& eid, const std::string& type, const std::string& label,
                 const std::string& parent, const Pose& pose, const ObjectSpec* object = nullptr) -> WorldElement& {
    WorldElement e;
    e.kind = kind;
    e.id = eid;
    e.type = type;
    e.label = label;
    e.parent = parent;
    e.pose = pose;
    e.object = object;
    out.push_back(std::move(e));
    return out.back();
  };
  for (const auto& f : scene.fixtures) {
    if (f.obstacle) continue;  // after the robots
    const std::string fid = id(f.type);
    add(WorldElement::Fixture, fid, f.type, f.name, "Scene-0", f.pose);
    for (const auto& o : scene.objects)
      if (o.on == f.name) add(WorldElement::Object, id(o.type), o.type, o.name, fid, relative_pose(f.pose, o.pose), &o);
  }
  for (const auto& o : scene.objects)
    if (o.on.empty()) add(WorldElement::Object, id(o.type), o.type, o.name, "Scene-0", o.pose, &o);
  const Pose identity{0, 0, 0, 0, 0, 0, 1};
  for (const auto& robot : scene.robots) {  // after everything else: one robot's ids stay as they were
    const std::string rid = id("Robot");
    add(WorldElement::Robot, rid, "Robot", robot.name, "Scene-0", robot.pose);
    add(WorldElement::Gripper, id("Gripper"), "Gripper", robot.gripper, rid, identity);
    add(WorldElement::Arm, id("Arm"), "Arm", robot.arm, rid, identity);
  }
  for (const auto& f : scene.fixtures)  // after the robots: a scene's obstacles renumber nothing else
    if (f.obstacle) add(WorldElement::Fixture, id(f.type), f.type, f.name, "Scene-0", f.pose);
  for (const auto& a : scene.articulated) {  // last of all, for the same reason
    const std::string aid = id(a.type);
    add(WorldElement::Articulated, aid, a.type, a.name, "Scene-0", a.pose);
    for (const auto& [joint, spec] : a.joints) {  // (a std::map: by joint name)
      WorldElement& e = add(WorldElement::ArticulatedPart, id(spec.type), spec.type, a.name + "/" + joint, aid, identity);
      e.joint = joint;
      const auto q = a.initial_joints.find(joint);
      e.joint_position = q == a.initial_joints.end() ? 0.0 : q->second;
    }
  }
  return out;
}

std::string to_turtle(const Scene& scene) {
  const std::vector<WorldElement> elements = world_elements(scene);
  std::map<std::string, std::vector<std::string>> children;  // parent id -> child ids, in order
  for (const auto& e : elements) children[e.parent].push_back(e.id);

  Triples t;
  t.subject("Scene-0");
  t.type("Scene");
  t.label(scene.name);
  t.string("FrameId", "map");
  for (const auto& c : children["Scene-0"]) t.relation("contain", c);
  for (const auto& e : elements) {
    t.subject(e.id);
    t.type(e.type);
    t.label(e.label);
    if (e.kind == WorldElement::Robot) {  // its position; it has its gripper and arm
      t.number("PositionX", e.pose[0]);
      t.number("PositionY", e.pose[1]);
      t.number("PositionZ", e.pose[2]);
      for (const auto& c : children[e.id]) t.relation("hasA", c);
      continue;
    }
    if (e.kind == WorldElement::Gripper || e.kind == WorldElement::Arm) continue;  // a label only
    if (e.kind == WorldElement::ArticulatedPart) {  // its joint (no pose: it moves with the joint)
      t.string("JointName", e.joint);
      t.number("JointPosition", e.joint_position);
      for (const auto& c : children[e.id]) t.relation("contain", c);
      continue;
    }
    static const char* const kPose[] = {"PositionX", "PositionY", "PositionZ", "OrientationX",
                                        "OrientationY", "OrientationZ", "OrientationW"};
    for (int i = 0; i < 7; ++i) t.number(kPose[i], e.pose[i]);
    if (e.object) {
      t.number("Size", e.object->shape == "box" ? e.object->size[0] : 2 * e.object->size[0]);
      t.number("Weight", e.object->mass);
    }
    for (const auto& c : children[e.id]) t.relation("contain", c);
  }
  wm::Prefixes prefixes;  // rdf, rdfs, owl, xsd, skiros
  return "# The " + one_line(scene.name) +
         " world (world-model side), generated by `skillbus scene turtle` (sb_scene turtle) from its scene file: "
         "do not edit, regenerate.\n" +
         wm::write_turtle(t.all(), prefixes);
}

}  // namespace skillbus::scene
