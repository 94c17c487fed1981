// Scene files: the demo scene loads; every kind of mistake is named with its field.
#include <gtest/gtest.h>

#include <cmath>

#include "skillbus/scene/scene.hpp"

using namespace skillbus::scene;

namespace {
const std::string kDir = SKILLBUS_TEST_SCENE_DIR;  // deploy/scenes

std::string scene_with(const std::string& objects, const std::string& physics = "{}") {
  return R"({"name": "t", "physics": )" + physics + R"(,
    "robot": {"name": "r", "urdf": "../../sim_server/models/arm6.urdf", "tool_link": "link6",
              "left_finger_joint": "finger_left_joint", "right_finger_joint": "finger_right_joint"},
    "fixtures": [{"name": "table", "urdf": "../../sim_server/models/table.urdf"}],
    "objects": )" + objects + "}";
}

std::string error_of(const std::string& text) {
  try {
    parse_scene(text, kDir + "/test.scene.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(Scene, TheDemoSceneLoads) {
  const Scene s = load_scene(kDir + "/demo.scene.json");
  EXPECT_EQ(s.name, "demo");
  ASSERT_EQ(s.objects.size(), 3u);
  EXPECT_EQ(s.objects[1].name, "green");
  EXPECT_EQ(s.objects[1].on, "table");
  EXPECT_DOUBLE_EQ(s.objects[1].pose[2], 0.425);
  ASSERT_EQ(s.fixtures.size(), 3u);  // the table, the bin, and the obstacle (the post) after them
  EXPECT_FALSE(s.fixtures[1].obstacle);
  EXPECT_TRUE(s.fixtures[2].obstacle);
  EXPECT_EQ(s.fixtures[2].name, "post");
  EXPECT_EQ(s.fixtures[2].type, "Obstacle");
  EXPECT_EQ(s.physics.collision_detector, "bullet");
  ASSERT_EQ(s.robots.size(), 1u);
  EXPECT_EQ(s.robots[0].tool_link, "link6");
  EXPECT_EQ(s.robots[0].bus_name, "");  // one robot: its channels have no namespace
  EXPECT_NE(s.robots[0].urdf.find("sim_server/models/arm6.urdf"), std::string::npos);
  EXPECT_EQ(&robot_on_bus(s, ""), &s.robots[0]);
  EXPECT_THROW(robot_on_bus(s, "r2"), SceneError);
}

TEST(Scene, SeveralRobotsEachOnTheirOwnBusName) {
  const Scene s = load_scene(kDir + "/two_arms.scene.json");
  ASSERT_EQ(s.robots.size(), 2u);
  EXPECT_EQ(s.robots[0].bus_name, "r1");
  EXPECT_EQ(s.robots[1].bus_name, "r2");
  EXPECT_DOUBLE_EQ(s.robots[1].pose[1], -1.6);
  EXPECT_EQ(robot_on_bus(s, "r2").gripper, "r2_gripper");
  try {
    robot_on_bus(s, "r3");
    ADD_FAILURE() << "no robot r3";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("no robot 'r3' (robots: r1, r2)"), std::string::npos) << e.what();
  }
  // Written out and read back: the same robots, still a list.
  const Scene again = parse_scene(to_json(s), s.path);
  ASSERT_EQ(again.robots.size(), 2u);
  EXPECT_EQ(again.robots[1].bus_name, "r2");
}

TEST(Scene, SeveralRobotsMistakesAreNamed) {
  const std::string robot = R"({"name": "NAME", "urdf": "../../sim_server/models/arm6.urdf", "tool_link": "link6",
      "left_finger_joint": "finger_left_joint", "right_finger_joint": "finger_right_joint", "arm": "ARM", "gripper": "GRIP"})";
  auto with = [&](std::string name, std::string arm, std::string grip) {
    std::string r = robot;
    r.replace(r.find("NAME"), 4, name);
    r.replace(r.find("ARM"), 3, arm);
    r.replace(r.find("GRIP"), 4, grip);
    return r;
  };
  auto scene = [](const std::string& robots) { return R"({"name": "t", "robots": [)" + robots + "]}"; };
  EXPECT_EQ(error_of(scene(with("a", "a_arm", "a_grip") + "," + with("b", "b_arm", "b_grip"))), "");
  EXPECT_NE(error_of(scene("")).find("robots must be a non-empty array"), std::string::npos);
  EXPECT_NE(error_of(scene(with("a", "x", "y") + "," + with("a", "z", "w"))).find("robots[1].name 'a' is used twice"),
            std::string::npos);
  EXPECT_NE(error_of(scene(with("a", "arm", "g1") + "," + with("b", "arm", "g2"))).find("robots[1].arm 'arm' is used twice among the robots"),
            std::string::npos);
  EXPECT_NE(error_of(scene(with("a/b", "x", "y"))).find("robots[0].name 'a/b' must be a letter"), std::string::npos);
  EXPECT_NE(error_of(scene(with("1a", "x", "y"))).find("must be a letter"), std::string::npos);
  const std::string both = R"({"name": "t", "robot": )" + with("a", "x", "y") + R"(, "robots": [])" + "}";
  EXPECT_NE(error_of(both).find("either robot or robots, not both"), std::string::npos);
}

TEST(Scene, MistakesAreNamedWithTheirField) {
  EXPECT_EQ(error_of(scene_with("[]")), "");
  EXPECT_NE(error_of("{not json").find("not valid JSON"), std::string::npos);
  EXPECT_NE(error_of(R"({"name": "x"})").find(": robot is missing"), std::string::npos);
  EXPECT_NE(error_of(scene_with(R"([{"name": "c", "shape": "box", "size": [0.05, 0.05, 0.05], "mass": -1}])"))
                .find("objects[0].mass must be > 0"), std::string::npos);
  EXPECT_NE(error_of(scene_with(R"([{"name": "c", "shape": "sphere"}])")).find("objects[0].shape must be"),
            std::string::npos);
  EXPECT_NE(error_of(scene_with(R"([{"name": "c", "shape": "box", "size": [0.05, 0.05]}])"))
                .find("objects[0].size must be an array of 3 numbers"), std::string::npos);
  EXPECT_NE(error_of(scene_with(R"([{"name": "table", "shape": "box", "size": [1, 1, 1]}])"))
                .find("'table' is used twice"), std::string::npos);
  EXPECT_NE(error_of(scene_with(R"([{"name": "c", "shape": "box", "size": [1, 1, 1], "on": "shelf"}])"))
                .find("objects[0].on names 'shelf', which is not a fixture"), std::string::npos);
  EXPECT_NE(error_of(scene_with(R"([{"name": "c", "shape": "box", "size": [1, 1, 1], "pose": [0, 0, 0, 0, 0, 0, 0]}])"))
                .find("objects[0].pose has a zero quaternion"), std::string::npos);
  EXPECT_NE(error_of(scene_with("[]", R"({"step_ms": 1, "frame_ms": 2.5})")).find("physics.frame_ms must be a whole number"),
            std::string::npos);
  EXPECT_NE(error_of(scene_with("[]", R"({"collision_detector": "ode"})")).find("physics.collision_detector must be one of"),
            std::string::npos);
  std::string missing = scene_with("[]");
  missing.replace(missing.find("arm6.urdf"), 9, "nope.urdf");
  EXPECT_NE(error_of(missing).find("robot.urdf names a file that does not exist"), std::string::npos);
}

namespace {
// The test scene's objects "[]" with `cameras` added.
std::string with_cameras(const std::string& cameras) {
  std::string s = scene_with("[]");
  s.insert(s.rfind('}'), R"(, "cameras": )" + cameras);
  return s;
}
}  // namespace

TEST(Scene, CamerasTakeTheirDefaultsAndComeBackFromJson) {
  const Scene s = parse_scene(with_cameras(R"([{"name": "overhead", "pose": [0.5, 0, 1.2, 1, 0, 0, 0]},
      {"name": "wrist", "robot": "r", "link": "link6", "width": 64, "height": 48,
       "intrinsics": [50, 51, 31.5, 23.5], "rate_hz": 2, "noise_stddev_m": 0.001, "seed": 9}])"),
                              kDir + "/test.scene.json");
  ASSERT_EQ(s.cameras.size(), 2u);
  const CameraSpec& a = s.cameras[0];
  EXPECT_EQ(a.width, 160);
  EXPECT_EQ(a.height, 120);
  EXPECT_NEAR(a.fy, 60.0 / std::tan(30.0 * M_PI / 180.0), 1e-9);  // 60 degrees vertical
  EXPECT_DOUBLE_EQ(a.fx, a.fy);
  EXPECT_DOUBLE_EQ(a.cx, 80);
  EXPECT_DOUBLE_EQ(a.cy, 60);
  EXPECT_EQ(a.rate_hz, 0);  // on request only
  EXPECT_EQ(a.noise_stddev_m, 0);
  const CameraSpec& b = s.cameras[1];
  EXPECT_EQ(b.robot, "r");
  EXPECT_EQ(b.link, "link6");
  EXPECT_DOUBLE_EQ(b.fy, 51);
  EXPECT_EQ(b.seed, 9u);
  const Scene again = parse_scene(to_json(s), s.path);
  ASSERT_EQ(again.cameras.size(), 2u);
  EXPECT_EQ(again.cameras[1].link, "link6");
  EXPECT_DOUBLE_EQ(again.cameras[0].fx, a.fx);
  EXPECT_EQ(again.cameras[1].seed, 9u);
  EXPECT_EQ(to_json(again), to_json(s));
}

TEST(Scene, CameraMistakesAreNamedWithTheirField) {
  auto err = [](const std::string& cams) { return error_of(with_cameras(cams)); };
  EXPECT_EQ(err(R"([{"name": "c"}])"), "");
  EXPECT_NE(err(R"({"name": "c"})").find("cameras must be an array"), std::string::npos);
  EXPECT_NE(err(R"([{}])").find("cameras[0].name is missing"), std::string::npos);
  EXPECT_NE(err(R"([{"name": "a b"}])").find("cameras[0].name 'a b' must be a letter"), std::string::npos);
  EXPECT_NE(err(R"([{"name": "c"}, {"name": "c"}])").find("cameras[1].name 'c' is used twice"), std::string::npos);
  EXPECT_NE(err(R"([{"name": "c", "link": "link6"}])").find("cameras[0].link needs robot and link"), std::string::npos);
  EXPECT_NE(err(R"([{"name": "c", "robot": "zz", "link": "l"}])").find("cameras[0].robot names 'zz'"), std::string::npos);
  EXPECT_NE(err(R"([{"name": "c", "width": 0}])").find("cameras[0].width must be a whole number"), std::string::npos);
  EXPECT_NE(err(R"([{"name": "c", "height": 2.5}])").find("cameras[0].height must be a whole number"), std::string::npos);
  EXPECT_NE(err(R"([{"name": "c", "width": 4096, "height": 4096}])").find("times height must be at most"),
            std::string::npos);
  EXPECT_NE(err(R"([{"name": "c", "fov_deg": 180}])").find("cameras[0].fov_deg must be between"), std::string::npos);
  EXPECT_NE(err(R"([{"name": "c", "fov_deg": 60, "intrinsics": [1, 1, 0, 0]}])").find("both given"), std::string::npos);
  EXPECT_NE(err(R"([{"name": "c", "intrinsics": [0, 1, 0, 0]}])").find("fx > 0"), std::string::npos);
  EXPECT_NE(err(R"([{"name": "c", "near": 0}])").find("cameras[0].near must be > 0"), std::string::npos);
  EXPECT_NE(err(R"([{"name": "c", "near": 1, "far": 1}])").find("cameras[0].far must be > near"), std::string::npos);
  EXPECT_NE(err(R"([{"name": "c", "rate_hz": -1}])").find("cameras[0].rate_hz must be >= 0"), std::string::npos);
  EXPECT_NE(err(R"([{"name": "c", "noise_stddev_m": -0.1}])").find("noise_stddev_m must be >= 0"), std::string::npos);
  EXPECT_NE(err(R"([{"name": "c", "seed": 1.5}])").find("cameras[0].seed must be a whole number"), std::string::npos);
  EXPECT_NE(err(R"([{"name": "c", "width": "wide"}])").find("cameras[0].width must be a number"), std::string::npos);
}

namespace {
// The test scene's objects "[]" with `articulated` added.
std::string with_articulated(const std::string& articulated) {
  std::string s = scene_with("[]");
  s.insert(s.rfind('}'), R"(, "articulated": )" + articulated);
  return s;
}
const std::string kCabinetUrdf = R"("urdf": "../../sim_server/models/cabinet.urdf")";
}  // namespace

TEST(Scene, TheCabinetSceneLoadsWithItsArticulatedObject) {
  const Scene s = load_scene(kDir + "/cabinet.scene.json");
  ASSERT_EQ(s.articulated.size(), 1u);
  const ArticulatedSpec& a = s.articulated[0];
  EXPECT_EQ(a.name, "cabinet");
  EXPECT_EQ(a.type, "Cabinet");
  EXPECT_NE(a.urdf.find("sim_server/models/cabinet.urdf"), std::string::npos);
  EXPECT_TRUE(a.urdf[0] == '/');
  EXPECT_NEAR(a.pose[5], std::sqrt(0.5), 1e-12);  // turned +90 degrees about z (and normalized)
  ASSERT_EQ(a.joints.size(), 2u);
  EXPECT_EQ(a.joints.begin()->first, "door_joint");  // by name
  const ArticulatedJointSpec& drawer = a.joints.at("drawer_joint");
  EXPECT_EQ(drawer.type, "Drawer");
  ASSERT_TRUE(drawer.damping && drawer.friction && drawer.handle);
  EXPECT_DOUBLE_EQ(*drawer.damping, 4.0);
  EXPECT_DOUBLE_EQ(*drawer.friction, 0.5);
  EXPECT_DOUBLE_EQ((*drawer.handle)[2], 0.32);
  EXPECT_EQ(a.initial_joints.at("drawer_joint"), 0.0);
  EXPECT_TRUE(s.fixtures.size() == 1 && s.objects.size() == 2 && s.cameras.empty());
  // Written out and read back: the same.
  const Scene again = parse_scene(to_json(s), s.path);
  EXPECT_EQ(to_json(again), to_json(s));
  ASSERT_EQ(again.articulated.size(), 1u);
  EXPECT_DOUBLE_EQ(*again.articulated[0].joints.at("door_joint").friction, 0.05);
  // A scene without articulated objects is written as before: no "articulated" at all.
  EXPECT_EQ(to_json(load_scene(kDir + "/demo.scene.json")).find("articulated"), std::string::npos);
}

TEST(Scene, ArticulatedObjectsTakeTheirDefaults) {
  const Scene s = parse_scene(with_articulated(R"([{"name": "box", )" + kCabinetUrdf + R"(, "joints": {"j": {}}}])"),
                              kDir + "/test.scene.json");
  ASSERT_EQ(s.articulated.size(), 1u);
  const ArticulatedSpec& a = s.articulated[0];
  EXPECT_EQ(a.type, "ArticulatedObject");
  EXPECT_DOUBLE_EQ(a.friction, 0.8);
  EXPECT_EQ(a.pose, (Pose{0, 0, 0, 0, 0, 0, 1}));
  EXPECT_TRUE(a.initial_joints.empty());
  const ArticulatedJointSpec& j = a.joints.at("j");
  EXPECT_EQ(j.type, "ArticulatedPart");
  EXPECT_FALSE(j.damping || j.friction || j.handle);  // the URDF's dynamics; no handle
  const std::string normalized = to_json(s);
  EXPECT_NE(normalized.find(R"("joints":{"j":{"type":"ArticulatedPart"}})"), std::string::npos) << normalized;
  EXPECT_NE(normalized.find(R"("initial_joints":{})"), std::string::npos) << normalized;
}

TEST(Scene, ArticulatedMistakesAreNamedWithTheirField) {
  auto err = [](const std::string& a) { return error_of(with_articulated(a)); };
  auto entry = [](const std::string& fields) { return R"([{"name": "c", )" + kCabinetUrdf + ", " + fields + "}]"; };
  auto joint = [&](const std::string& fields) { return entry(R"("joints": {"j": {)" + fields + "}}"); };
  EXPECT_EQ(err(joint("")), "");
  EXPECT_NE(err(R"({"name": "c"})").find("articulated must be an array"), std::string::npos);
  EXPECT_NE(err(R"([{"urdf": "x"}])").find("articulated[0].name is missing"), std::string::npos);
  EXPECT_NE(err(R"([{"name": "table", )" + kCabinetUrdf + R"(, "joints": {"j": {}}}])").find("articulated[0].name 'table' is used twice in the scene"),
            std::string::npos);
  EXPECT_NE(err(R"([{"name": "r", )" + kCabinetUrdf + R"(, "joints": {"j": {}}}])").find("articulated[0].name 'r' is used twice"),
            std::string::npos);  // the robot's name
  EXPECT_NE(err(R"([{"name": "c", "joints": {"j": {}}}])").find("articulated[0].urdf is missing"), std::string::npos);
  EXPECT_NE(err(R"([{"name": "c", "urdf": "nope.urdf", "joints": {"j": {}}}])").find("articulated[0].urdf names a file that does not exist"),
            std::string::npos);
  EXPECT_NE(err(entry(R"("type": "Big Cabinet", "joints": {"j": {}})")).find("articulated[0].type must be a concept name"),
            std::string::npos);
  EXPECT_NE(err(entry(R"("friction": -1, "joints": {"j": {}})")).find("articulated[0].friction must be >= 0"), std::string::npos);
  EXPECT_NE(err(entry(R"("pose": [0, 0, 0, 0, 0, 0, 0], "joints": {"j": {}})")).find("articulated[0].pose has a zero quaternion"),
            std::string::npos);
  EXPECT_NE(err(entry(R"("initial_joints": [1], "joints": {"j": {}})")).find("articulated[0].initial_joints must be an object {joint: position}"),
            std::string::npos);
  EXPECT_NE(err(entry(R"("initial_joints": {"j": "open"}, "joints": {"j": {}})")).find("articulated[0].initial_joints.j must be a finite number"),
            std::string::npos);
  EXPECT_NE(err(entry(R"("type": "Cabinet")")).find("articulated[0].joints is missing"), std::string::npos);
  EXPECT_NE(err(entry(R"("joints": {})")).find("articulated[0].joints must be a non-empty object"), std::string::npos);
  EXPECT_NE(err(entry(R"("joints": ["j"])")).find("articulated[0].joints must be a non-empty object"), std::string::npos);
  EXPECT_NE(err(entry(R"("joints": {"j": 1})")).find("articulated[0].joints.j must be an object"), std::string::npos);
  EXPECT_NE(err(joint(R"("type": "a door")")).find("articulated[0].joints.j.type must be a concept name"), std::string::npos);
  EXPECT_NE(err(joint(R"("damping": -0.1)")).find("articulated[0].joints.j.damping must be >= 0"), std::string::npos);
  EXPECT_NE(err(joint(R"("friction": -0.1)")).find("articulated[0].joints.j.friction must be >= 0"), std::string::npos);
  EXPECT_NE(err(joint(R"("damping": "high")")).find("articulated[0].joints.j.damping must be a number"), std::string::npos);
  EXPECT_NE(err(joint(R"("handle": [0, 0, 0])")).find("articulated[0].joints.j.handle must be an array of 7 numbers"),
            std::string::npos);
  EXPECT_NE(err(joint(R"("handle": [0, 0, 0, 0, 0, 0, 0])")).find("articulated[0].joints.j.handle has a zero quaternion"),
            std::string::npos);
  // The message names the file too.
  EXPECT_EQ(err(joint(R"("friction": -0.1)")).rfind(kDir + "/test.scene.json: ", 0), 0u);
}
