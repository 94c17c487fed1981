// Articulated objects and attach/detach in a real DART world (deploy/scenes/cabinet.scene.json):
// the cabinet's joints as SB_ROBOT_ARTICULATION reports them (axes, hinge, handles where
// the model puts them), their friction, damping and limits under a gravity tilted along
// the drawer, what the scene may not name, objects in the drawer, and an object welded to
// the tool that follows it and falls once let go. Physics only, no bus.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "skillbus/scene/scene.hpp"
#include "skillbus/sim/physics.hpp"

using namespace skillbus;
using nlohmann::json;

namespace {
const std::string kDir = SKILLBUS_TEST_SCENE_DIR;  // deploy/scenes

json cabinet_json() {
  std::ifstream in(kDir + "/cabinet.scene.json");
  return json::parse(in);
}

// A scene from the cabinet's, changed (read from the scenes folder: relative URDF paths hold).
scene::Scene scene_of(const json& j) { return scene::parse_scene(j.dump(), kDir + "/articulated_test.scene.json"); }

Eigen::Isometry3d iso(const double* p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(p[0], p[1], p[2]);
  T.linear() = Eigen::Quaterniond(p[6], p[3], p[4], p[5]).normalized().toRotationMatrix();
  return T;
}

const skillbus_msgs::articulated_joint_t& joint(const skillbus_msgs::articulation_state_t& s, const std::string& name) {
  for (const auto& j : s.joints)
    if (j.joint == name) return j;
  throw std::runtime_error("no joint " + name);
}

skillbus_msgs::articulation_state_t articulation(const sim::Physics& p) {
  skillbus_msgs::articulation_state_t s{};
  p.fill_articulation(0, s);
  return s;
}

double position(const sim::Physics& p, const std::string& name) { return joint(articulation(p), name).position; }

Eigen::Vector3d vec(const double* v) { return Eigen::Vector3d(v[0], v[1], v[2]); }

std::string error_of(const json& j) {
  try {
    sim::Physics p(scene_of(j));
  } catch (const scene::SceneError& e) {
    return e.what();
  }
  return "";
}

const skillbus_msgs::robot_object_t& object(const skillbus_msgs::robot_objects_t& o, const std::string& name) {
  for (const auto& x : o.objects)
    if (x.name == name) return x;
  throw std::runtime_error("no object " + name);
}
}  // namespace

TEST(Articulated, TheCabinetReportsBothJointsWithTheirAxesAndHandles) {
  sim::Physics p(scene::load_scene(kDir + "/cabinet.scene.json"));
  const auto s = articulation(p);
  ASSERT_EQ(s.num_joints, 2);
  ASSERT_EQ(s.joints.size(), 2u);
  // by joint name: door_joint before drawer_joint
  const auto& door = s.joints[0];
  const auto& drawer = s.joints[1];
  EXPECT_EQ(door.joint, "door_joint");
  EXPECT_EQ(drawer.joint, "drawer_joint");
  EXPECT_EQ(drawer.object, "cabinet");
  EXPECT_EQ(drawer.concept, "Drawer");
  EXPECT_EQ(door.concept, "Door");
  EXPECT_EQ(drawer.kind, "prismatic");
  EXPECT_EQ(door.kind, "revolute");
  EXPECT_DOUBLE_EQ(drawer.position, 0.0);
  EXPECT_DOUBLE_EQ(door.position, 0.0);
  EXPECT_DOUBLE_EQ(drawer.lower, 0.0);
  EXPECT_DOUBLE_EQ(drawer.upper, 0.25);
  EXPECT_DOUBLE_EQ(door.upper, 1.9);
  // The cabinet turned +90 degrees about z: its front (+x) faces world +y, the robot.
  EXPECT_LT((vec(drawer.axis) - Eigen::Vector3d(0, 1, 0)).norm(), 1e-9);
  EXPECT_LT((vec(door.axis) - Eigen::Vector3d(0, 0, 1)).norm(), 1e-9);
  // The hinge: the door's outer front edge, at world x -0.25, on the front plane y -0.40.
  EXPECT_NEAR(door.origin[0], -0.25, 1e-9);
  EXPECT_NEAR(door.origin[1], -0.40, 1e-9);
  EXPECT_NEAR(drawer.origin[1], -0.40, 1e-9);
  ASSERT_TRUE(drawer.has_handle && door.has_handle);
  EXPECT_LT((vec(drawer.handle_pose) - Eigen::Vector3d(0.12, -0.33, 0.32)).norm(), 1e-9);
  EXPECT_LT((vec(door.handle_pose) - Eigen::Vector3d(-0.035, -0.33, 0.32)).norm(), 1e-9);
  for (const auto* j : {&drawer, &door}) {
    const Eigen::Matrix3d R = iso(j->handle_pose).linear();
    EXPECT_LT((R.col(2) - Eigen::Vector3d(0, 0, -1)).norm(), 1e-9) << j->joint << ": the tool points down";
    // The fingers (the tool's y) close along the pull, across the bar: world y.
    EXPECT_NEAR(std::abs(R.col(1).y()), 1.0, 1e-9) << j->joint;
  }
  // Left alone, nothing moves.
  for (int f = 0; f < 50; ++f) p.step_frame();
  const auto after = articulation(p);
  EXPECT_NEAR(joint(after, "drawer_joint").position, 0.0, 1e-6);
  EXPECT_NEAR(joint(after, "door_joint").position, 0.0, 1e-6);
}

TEST(Articulated, HandlesAndAxesFollowTheJoints) {
  json j = cabinet_json();
  j["articulated"][0]["initial_joints"] = {{"drawer_joint", 0.2}, {"door_joint", M_PI / 2}};
  sim::Physics p(scene_of(j));
  const auto s = articulation(p);
  const auto& drawer = joint(s, "drawer_joint");
  const auto& door = joint(s, "door_joint");
  EXPECT_DOUBLE_EQ(drawer.position, 0.2);
  EXPECT_LT((vec(drawer.handle_pose) - Eigen::Vector3d(0.12, -0.13, 0.32)).norm(), 1e-9);  // 0.2 m toward the robot
  EXPECT_LT((vec(drawer.axis) - Eigen::Vector3d(0, 1, 0)).norm(), 1e-9);
  // The door open a quarter turn: its handle, 0.215 m along the door from the hinge and
  // 0.07 m out of it, has swung from in front of the cabinet to beside the hinge.
  EXPECT_LT((vec(door.handle_pose) - Eigen::Vector3d(-0.25 - 0.07, -0.40 + 0.215, 0.32)).norm(), 1e-9);
  EXPECT_LT((vec(door.origin) - Eigen::Vector3d(-0.25, -0.40, 0)).norm(), 1e-9);  // the hinge stays
  EXPECT_LT((iso(door.handle_pose).linear().col(2) - Eigen::Vector3d(0, 0, -1)).norm(), 1e-9);
}

// Gravity tilted sideways: along world +y it pulls the drawer out and swings the door
// open (toward +y, about its vertical hinge). A sideways part smaller than the joints'
// friction holds them; without friction they move; a large one drives them to their
// limits, where they stop.
TEST(Articulated, FrictionHoldsAndTheLimitsStopTheJoints) {
  // joints_extra: {joint: {field: value}}, a null value removes the field.
  auto run = [](double gx, double gy, const json& joints_extra, int frames) {
    json j = cabinet_json();
    j.erase("objects");  // (the cubes would slide off the table)
    j["physics"]["gravity"] = {gx, gy, -9.81};
    j["articulated"][0]["initial_joints"] = {{"drawer_joint", 0.1}, {"door_joint", 0.5}};
    for (auto it = joints_extra.begin(); it != joints_extra.end(); ++it)
      for (auto f = it.value().begin(); f != it.value().end(); ++f) {
        json& spec = j["articulated"][0]["joints"][it.key()];
        if (f.value().is_null()) {
          spec.erase(f.key());
        } else {
          spec[f.key()] = f.value();
        }
      }
    sim::Physics p(scene_of(j));
    for (int f = 0; f < frames; ++f) p.step_frame();
    return std::make_pair(position(p, "drawer_joint"), position(p, "door_joint"));
  };
  // 0.3 m/s^2 along +y pushes the 1 kg drawer with 0.3 N (its friction: 0.5 N) and turns
  // the door with about 0.034 N m (0.05 N m).
  auto [drawer, door] = run(0, 0.3, json::object(), 50);
  EXPECT_NEAR(drawer, 0.1, 1e-4);
  EXPECT_NEAR(door, 0.5, 1e-4);
  // The URDF's friction (the same values) when the scene gives none.
  std::tie(drawer, door) = run(0, 0.3, {{"drawer_joint", {{"friction", nullptr}}}, {"door_joint", {{"friction", nullptr}}}}, 50);
  EXPECT_NEAR(drawer, 0.1, 1e-4);
  EXPECT_NEAR(door, 0.5, 1e-4);
  // Without friction both move (the drawer at up to 0.3 N / 4 N s/m: 0.057 m in 1 s; the
  // door by 0.06 rad).
  std::tie(drawer, door) = run(0, 0.3, {{"drawer_joint", {{"friction", 0.0}}}, {"door_joint", {{"friction", 0.0}}}}, 50);
  EXPECT_GT(drawer, 0.14);
  EXPECT_GT(door, 0.53);
  // More damping, less motion.
  const double slow = run(0, 0.3, {{"drawer_joint", {{"friction", 0.0}, {"damping", 40.0}}}}, 50).first;
  EXPECT_GT(slow, 0.1 + 1e-4);
  EXPECT_LT(slow - 0.1, 0.3 * (drawer - 0.1));
  // 5 m/s^2 toward (-0.8, 0.6), beyond the door's upper limit (1.9 rad; the cabinet's
  // front faces +y, so the door points along (cos q, sin q) from its hinge): both go to
  // their upper limits and stay there...
  std::tie(drawer, door) = run(-4, 3, json::object(), 200);
  EXPECT_GT(drawer, 0.25 - 1e-3);
  EXPECT_LT(drawer, 0.25 + 1e-3);
  EXPECT_GT(door, 1.9 - 1e-2);
  EXPECT_LT(door, 1.9 + 1e-2);
  // ...and the other way to their lower limits.
  std::tie(drawer, door) = run(4, -3, json::object(), 200);
  EXPECT_GT(drawer, -1e-3);
  EXPECT_LT(drawer, 1e-3);
  EXPECT_GT(door, -1e-2);
  EXPECT_LT(door, 1e-2);
}

TEST(Articulated, JointsTheUrdfDoesNotHaveAreRefused) {
  json j = cabinet_json();
  j["articulated"][0]["initial_joints"] = {{"drawer_joint", 0.3}};
  EXPECT_NE(error_of(j).find("articulated[0].initial_joints.drawer_joint is outside the joint's limits"), std::string::npos)
      << error_of(j);
  j["articulated"][0]["initial_joints"] = {{"nope", 0.1}};
  EXPECT_NE(error_of(j).find("articulated[0].initial_joints names 'nope', not a 1-DoF prismatic or revolute joint of /"),
            std::string::npos)
      << error_of(j);
  j = cabinet_json();
  j["articulated"][0]["joints"]["lid_joint"] = json::object();
  EXPECT_NE(error_of(j).find("articulated[0].joints names 'lid_joint', not a 1-DoF prismatic or revolute joint of /"),
            std::string::npos)
      << error_of(j);
  EXPECT_NE(error_of(j).find("cabinet.urdf"), std::string::npos);
  j = cabinet_json();
  j["articulated"][0]["initial_joints"] = {{"drawer_joint", 0.25}, {"door_joint", 0.0}};  // the limits themselves
  EXPECT_EQ(error_of(j), "");
}

TEST(Articulated, AnObjectInTheDrawerRestsOnIt) {
  json j = cabinet_json();
  // The tray's inside: x -0.21..-0.01 in the drawer's frame, whose origin is 0.15 m in
  // front of the cabinet's middle at y -0.12: its centre is at world (0.12, -0.51); the
  // plate's top at 0.255 m.
  j["objects"].push_back({{"name", "box"}, {"type", "Cube"}, {"shape", "box"}, {"size", {0.05, 0.05, 0.05}},
                          {"mass", 0.2}, {"pose", {0.12, -0.51, 0.285, 0, 0, 0, 1}}});
  sim::Physics p(scene_of(j));
  for (int f = 0; f < 50; ++f) p.step_frame();
  skillbus_msgs::robot_objects_t o{};
  p.fill_objects(o);
  const auto& box = object(o, "box");
  EXPECT_NEAR(box.pose[2], 0.28, 2e-3);  // on the plate, under the cabinet's top (0.315)
  EXPECT_NEAR(box.pose[0], 0.12, 1e-3);
  EXPECT_EQ(box.support, "cabinet/drawer_joint");  // the world model's label of the drawer
  EXPECT_EQ(object(o, "red").support, "table");
  EXPECT_NEAR(position(p, "drawer_joint"), 0.0, 1e-4);
}

namespace {
// The cabinet scene with a cube ("probe") 1 cm beyond the tool centre point, under the
// tool of the arm as it starts (pointing down).
json scene_with_probe() {
  sim::Physics first(scene::load_scene(kDir + "/cabinet.scene.json"));
  skillbus_msgs::robot_arm_state_t a{};
  first.fill_arm_state(0, a);
  const Eigen::Vector3d down = iso(a.tool_pose).linear().col(2);
  EXPECT_LT((down - Eigen::Vector3d(0, 0, -1)).norm(), 1e-3) << "the demo arm starts with its tool down";
  const Eigen::Vector3d at = vec(a.tool_pose) + 0.01 * down;
  json j = cabinet_json();
  j["objects"].push_back({{"name", "probe"}, {"type", "Cube"}, {"shape", "box"}, {"size", {0.04, 0.04, 0.04}},
                          {"mass", 0.2}, {"pose", {at.x(), at.y(), at.z(), 0, 0, 0, 1}}});
  return j;
}

Eigen::Isometry3d tool_of(const sim::Physics& p) {
  skillbus_msgs::robot_arm_state_t a{};
  p.fill_arm_state(0, a);
  return iso(a.tool_pose);
}

Eigen::Isometry3d pose_of(const sim::Physics& p, const std::string& name) {
  skillbus_msgs::robot_objects_t o{};
  p.fill_objects(o);
  return iso(object(o, name).pose);
}

// The shoulder and elbow back toward upright: the tool rises and comes nearer the base.
sim::ArmCommand raise(const std::string& id = "up") {
  sim::ArmCommand c;
  c.id = id;
  c.joints = {"joint2", "joint3"};
  sim::Waypoint w;
  w.t_ns = 0;
  w.q = {0.0, 1.2};
  c.points.push_back(w);
  return c;
}
}  // namespace

TEST(Attach, AnAttachedObjectFollowsTheToolAndFallsWhenLetGo) {
  sim::Physics p(scene_of(scene_with_probe()));
  const Eigen::Isometry3d start = pose_of(p, "probe");
  const Eigen::Isometry3d held = tool_of(p).inverse() * start;
  ASSERT_EQ(p.attach(0, "probe", true), "");
  skillbus_msgs::robot_objects_t o{};
  p.fill_objects(o);
  EXPECT_EQ(object(o, "probe").support, "gripper");  // held by the robot's gripper, by its label
  ASSERT_EQ(p.command_arm(0, raise()), "");
  double worst = 0, worst_angle = 0;
  for (int f = 0; f < 100; ++f) {  // 2 s: the move and its settling
    p.step_frame();
    const Eigen::Isometry3d now = tool_of(p).inverse() * pose_of(p, "probe");
    worst = std::max(worst, (now.translation() - held.translation()).norm());
    worst_angle = std::max(worst_angle, Eigen::AngleAxisd(now.linear().transpose() * held.linear()).angle());
  }
  const Eigen::Isometry3d lifted = pose_of(p, "probe");
  EXPECT_GT(lifted.translation().z() - start.translation().z(), 0.1) << "the arm did not lift the probe";
  EXPECT_LT(worst, 2e-3) << "the probe moved in the tool's frame by " << worst * 1e3 << " mm";
  EXPECT_LT(worst_angle, 0.02);
  p.fill_objects(o);
  EXPECT_EQ(object(o, "probe").support, "gripper");

  ASSERT_EQ(p.attach(0, "probe", false), "");
  EXPECT_EQ(p.attach(0, "probe", false), "");  // not attached: nothing to do
  for (int f = 0; f < 15; ++f) p.step_frame();  // 0.3 s: about 0.44 m of free fall
  EXPECT_LT(pose_of(p, "probe").translation().z(), lifted.translation().z() - 0.2) << "the probe did not fall";
  EXPECT_GT((tool_of(p).translation() - pose_of(p, "probe").translation()).norm(), 0.2);
}

TEST(Attach, MistakesAreNamed) {
  sim::Physics p(scene_of(scene_with_probe()));
  EXPECT_EQ(p.attach(0, "nope", true), "unknown object 'nope' (the scene's objects: red, green, probe)");
  EXPECT_EQ(p.attach(0, "nope", false), "unknown object 'nope' (the scene's objects: red, green, probe)");
  const std::string far = p.attach(0, "red", true);
  EXPECT_EQ(far.rfind("object 'red' is ", 0), 0u) << far;
  EXPECT_NE(far.find(" m from the tool centre point of arm_robot: attach needs it within 0.10 m"), std::string::npos) << far;
  // (the distance itself, to the centimetre)
  const double d = (pose_of(p, "red").translation() - tool_of(p).translation()).norm();
  char text[32];
  std::snprintf(text, sizeof text, "is %.2f m", d);
  EXPECT_NE(far.find(text), std::string::npos) << far;
  EXPECT_EQ(p.attach(0, "probe", true), "");
  EXPECT_EQ(p.attach(0, "probe", true), "object 'probe' is already attached to arm_robot");
  EXPECT_THROW(p.attach(1, "probe", true), std::out_of_range);
  // Detach everything ("") lets it go; a reset drops attachments too.
  EXPECT_EQ(p.attach(0, "", false), "");
  EXPECT_EQ(p.attach(0, "probe", true), "");
  p.reset();
  EXPECT_EQ(p.attach(0, "probe", true), "") << "the reset world has no attachment";
  skillbus_msgs::robot_objects_t o{};
  p.reset();
  p.step_frame();
  p.fill_objects(o);
  EXPECT_NE(object(o, "probe").support, "gripper");
}

TEST(Attach, TheSameCommandsGiveTheSameWorld) {
  const scene::Scene s = scene_of(scene_with_probe());
  auto run = [&](bool attach) {
    sim::Physics p(s);
    if (attach) {
      EXPECT_EQ(p.attach(0, "probe", true), "");
    }
    EXPECT_EQ(p.command_arm(0, raise()), "");
    for (int f = 0; f < 40; ++f) p.step_frame();
    if (attach) {
      EXPECT_EQ(p.attach(0, "", false), "");
    }
    for (int f = 0; f < 10; ++f) p.step_frame();
    return p.digest();
  };
  const auto a = run(true), b = run(true), c = run(false);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);  // (the attachment made a difference)
}

TEST(Articulated, ASceneWithoutArticulatedObjectsReportsNoJoints) {
  sim::Physics p(scene::load_scene(kDir + "/demo.scene.json"));
  skillbus_msgs::articulation_state_t s{};
  p.fill_articulation(0, s);
  EXPECT_EQ(s.num_joints, 0);
  EXPECT_TRUE(s.joints.empty());
  EXPECT_THROW(p.fill_articulation(1, s), std::out_of_range);
}

namespace {
// The demo arm's joints that put the tool centre point at (x, y, z) pointing down, the
// fingers closing along the world direction at `yaw` from +y (closed form, as
// py_skills/skillbus/sim/arm_poses.py's top_down).
std::vector<double> top_down(double x, double y, double z, double yaw) {
  const double upper = 0.35, forearm = 0.34, shoulder_z = 0.5, wrist_to_tcp = 0.115;
  const double j1 = std::atan2(y, x), r = std::hypot(x, y), h = z + wrist_to_tcp - shoulder_z;
  const double q3 = std::acos((r * r + h * h - upper * upper - forearm * forearm) / (2 * upper * forearm));
  const double q2 = std::atan2(r, h) - std::atan2(forearm * std::sin(q3), upper + forearm * std::cos(q3));
  return {j1, q2, q3, 0.0, M_PI - q2 - q3, j1 - yaw};
}

const std::vector<std::string> kArm = {"joint1", "joint2", "joint3", "joint4", "joint5", "joint6"};

// A trajectory through `poses` (x y z yaw), `dt` seconds apart (a single pose: a
// minimum-jerk move timed by the velocity limits).
sim::ArmCommand through(const std::vector<std::array<double, 4>>& poses, double dt, const std::string& id) {
  sim::ArmCommand c;
  c.id = id;
  c.joints = kArm;
  for (size_t i = 0; i < poses.size(); ++i) {
    sim::Waypoint w;
    w.t_ns = poses.size() == 1 ? 0 : static_cast<int64_t>(std::llround((i + 1) * dt * 1e9));
    w.q = top_down(poses[i][0], poses[i][1], poses[i][2], poses[i][3]);
    c.points.push_back(w);
  }
  return c;
}

// Steps until the arm has played its trajectory, and 0.2 s more.
void settle(sim::Physics& p, int max_frames = 500) {
  skillbus_msgs::robot_arm_state_t a{};
  for (int f = 0; f < max_frames; ++f) {
    p.step_frame();
    p.fill_arm_state(0, a);
    if (!a.arm_moving) break;
  }
  for (int f = 0; f < 10; ++f) p.step_frame();
}
}  // namespace

// What a drawer-opening skill does, with the handle pose the physics reports: the arm
// comes down on the handle from above (fingers fully open), closes the fingers on the
// bar, and pulls along the drawer's axis; the drawer follows the hand.
TEST(Articulated, TheArmOpensTheDrawerByItsHandle) {
  sim::Physics p(scene::load_scene(kDir + "/cabinet.scene.json"));
  const auto& h = joint(articulation(p), "drawer_joint").handle_pose;
  const double x = h[0], y = h[1], z = h[2];
  ASSERT_EQ(p.command_arm(0, through({{x, y, z + 0.1, 0}}, 0, "above")), "");
  settle(p);
  ASSERT_EQ(p.command_arm(0, through({{x, y, z, 0}}, 0, "down")), "");
  settle(p);
  EXPECT_LT((tool_of(p).translation() - Eigen::Vector3d(x, y, z)).norm(), 5e-3) << "the fingers did not get around the bar";
  EXPECT_NEAR(position(p, "drawer_joint"), 0.0, 1e-3);
  ASSERT_EQ(p.command_gripper(0, sim::GripperCommand{"close", 0.0, 0.1, 20.0}), "");
  for (int f = 0; f < 50; ++f) p.step_frame();
  skillbus_msgs::sim_state_t st{};
  p.fill_state(0, st);
  // On the 2 cm bar (the pads, squeezing with 20 N, sink about a millimetre into it).
  EXPECT_GT(st.finger_width, 0.015);
  EXPECT_LT(st.finger_width, 0.0205);
  ASSERT_FALSE(st.contacts.empty());
  for (const auto& c : st.contacts) EXPECT_EQ(c.body_b, "cabinet") << c.body_a;
  std::vector<std::array<double, 4>> pull;
  for (int i = 1; i <= 10; ++i) pull.push_back({x, y + 0.02 * i, z, 0});  // 0.2 m along the axis (world +y)
  ASSERT_EQ(p.command_arm(0, through(pull, 0.25, "pull")), "");
  settle(p);
  EXPECT_NEAR(position(p, "drawer_joint"), 0.2, 0.01);
  const auto& now = joint(articulation(p), "drawer_joint").handle_pose;
  EXPECT_LT((vec(now) - tool_of(p).translation()).norm(), 0.01) << "the handle is in the hand";
}

// The same for the door: the hand follows the handle's arc about the hinge, turning with
// it, and the door opens by a radian.
TEST(Articulated, TheArmOpensTheDoorByItsHandle) {
  sim::Physics p(scene::load_scene(kDir + "/cabinet.scene.json"));
  const auto d = joint(articulation(p), "door_joint");
  const Eigen::Vector3d hinge = vec(d.origin), handle = vec(d.handle_pose);
  // The fingers close along the door's normal, world y at first (yaw 0, or pi: the
  // wrist's roll is nearer its middle so).
  const double yaw0 = -M_PI;
  ASSERT_EQ(p.command_arm(0, through({{handle.x(), handle.y(), handle.z() + 0.1, yaw0}}, 0, "above")), "");
  settle(p);
  ASSERT_EQ(p.command_arm(0, through({{handle.x(), handle.y(), handle.z(), yaw0}}, 0, "down")), "");
  settle(p);
  EXPECT_LT((tool_of(p).translation() - handle).norm(), 5e-3);
  ASSERT_EQ(p.command_gripper(0, sim::GripperCommand{"close", 0.0, 0.1, 20.0}), "");
  for (int f = 0; f < 50; ++f) p.step_frame();
  std::vector<std::array<double, 4>> arc;
  const Eigen::Vector3d r = handle - hinge;
  for (int i = 1; i <= 10; ++i) {
    const double a = 0.1 * i;  // rad
    const Eigen::Vector3d at = hinge + Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()) * r;
    arc.push_back({at.x(), at.y(), handle.z(), yaw0 + a});
  }
  ASSERT_EQ(p.command_arm(0, through(arc, 0.3, "open")), "");
  settle(p);
  EXPECT_NEAR(position(p, "door_joint"), 1.0, 0.05);
}
