// The world model's Turtle scene made from a scene file (sb_scene turtle): element ids in
// the file's order, poses relative to the container, numbers rounded, and labels escaped so
// that the world model's own reader gives them back unchanged.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <map>

#include "skillbus/scene/scene.hpp"
#include "skillbus/scene/turtle.hpp"
#include "skillbus/wm/ontology.hpp"
#include "skillbus/wm/rdf.hpp"
#include "skillbus/wm/scene.hpp"
#include "skillbus/wm/store.hpp"

using namespace skillbus::scene;
namespace wm = skillbus::wm;

namespace {
const std::string kDir = SKILLBUS_TEST_SCENE_DIR;  // deploy/scenes
const std::string kSkiros = "http://rvmi.aau.dk/ontologies/skiros.owl#";

Scene scene_of(const std::string& name, const std::string& fixtures, const std::string& objects,
               const std::string& robot_extra = "") {
  const std::string text = R"({"name": )" + name + R"(,
    "robot": {"name": "r", "urdf": "../../sim_server/models/arm6.urdf", "tool_link": "link6",
              "left_finger_joint": "finger_left_joint", "right_finger_joint": "finger_right_joint")" +
                           robot_extra + R"(},
    "fixtures": )" + fixtures + R"(, "objects": )" + objects + "}";
  return parse_scene(text, kDir + "/test.scene.json");
}

const std::string kTable = R"({"name": "table", "type": "Table", "urdf": "../../sim_server/models/table.urdf",
                                "pose": [0.5, 0, 0, 0, 0, 0, 1]})";
const std::string kBin = R"({"name": "bin", "type": "Bin", "urdf": "../../sim_server/models/bin.urdf",
                              "pose": [0, 0.6, 0, 0, 0, 0, 1]})";
std::string cube(const std::string& name, const std::string& on) {
  return R"({"name": ")" + name + R"(", "type": "Cube", "shape": "box", "size": [0.05, 0.05, 0.05],
             "pose": [0.4, 0.1, 0.425, 0, 0, 0, 1])" + (on.empty() ? "" : R"(, "on": ")" + on + "\"") + "}";
}

// The Turtle read back by the world model's reader: subject -> predicate -> objects, all
// compacted ("skiros:Table-1"), literals as their text.
using Graph = std::map<std::string, std::map<std::string, std::vector<std::string>>>;
Graph read_back(const std::string& turtle) {
  wm::Prefixes px;
  Graph g;
  for (const auto& t : wm::parse_turtle(turtle, px, "test"))
    g[px.compact(t.s.value)][px.compact(t.p.value)].push_back(t.o.kind == wm::Term::Literal ? t.o.value
                                                                                           : px.compact(t.o.value));
  return g;
}
}  // namespace

TEST(SceneTurtle, IdsFollowTheFile) {
  // b is on nothing, d on the bin, a and c on the table: each fixture is followed by its
  // objects (in file order), then the objects on nothing, then robot, gripper, arm.
  const Scene s = scene_of(R"("t")", "[" + kTable + ", " + kBin + "]",
                           "[" + cube("a", "table") + ", " + cube("b", "") + ", " + cube("c", "table") + ", " +
                               cube("d", "bin") + "]");
  std::vector<std::string> ids, labels, parents;
  for (const auto& e : world_elements(s)) {
    ids.push_back(e.id);
    labels.push_back(e.label);
    parents.push_back(e.parent);
  }
  EXPECT_EQ(ids, (std::vector<std::string>{"Table-1", "Cube-2", "Cube-3", "Bin-4", "Cube-5", "Cube-6", "Robot-7",
                                           "Gripper-8", "Arm-9"}));
  EXPECT_EQ(labels, (std::vector<std::string>{"table", "a", "c", "bin", "d", "b", "r", "gripper", "arm"}));
  EXPECT_EQ(parents, (std::vector<std::string>{"Scene-0", "Table-1", "Table-1", "Scene-0", "Bin-4", "Scene-0",
                                               "Scene-0", "Robot-7", "Robot-7"}));

  Graph g = read_back(to_turtle(s));
  EXPECT_EQ(g["skiros:Scene-0"]["skiros:contain"],
            (std::vector<std::string>{"skiros:Table-1", "skiros:Bin-4", "skiros:Cube-6", "skiros:Robot-7"}));
  EXPECT_EQ(g["skiros:Scene-0"]["skiros:FrameId"], std::vector<std::string>{"map"});
  EXPECT_EQ(g["skiros:Table-1"]["skiros:contain"], (std::vector<std::string>{"skiros:Cube-2", "skiros:Cube-3"}));
  EXPECT_EQ(g["skiros:Robot-7"]["skiros:hasA"], (std::vector<std::string>{"skiros:Gripper-8", "skiros:Arm-9"}));
  EXPECT_EQ(g["skiros:Cube-2"]["rdf:type"], (std::vector<std::string>{"skiros:Cube", "owl:NamedIndividual"}));
  // positions relative to the container: a at x 0.4 on the table at x 0.5; b in the world
  EXPECT_EQ(g["skiros:Cube-2"]["skiros:PositionX"], std::vector<std::string>{"-0.1"});
  EXPECT_EQ(g["skiros:Cube-6"]["skiros:PositionX"], std::vector<std::string>{"0.4"});
  EXPECT_EQ(g["skiros:Cube-5"]["skiros:PositionY"], std::vector<std::string>{"-0.5"});
  EXPECT_EQ(g["skiros:Cube-2"]["skiros:Size"], std::vector<std::string>{"0.05"});
  EXPECT_EQ(g["skiros:Cube-2"]["skiros:Weight"], std::vector<std::string>{"0.1"});
  EXPECT_EQ(g["skiros:Gripper-8"]["rdfs:label"], std::vector<std::string>{"gripper"});
  EXPECT_EQ(g["skiros:Gripper-8"].count("skiros:PositionX"), 0u);
}

TEST(SceneTurtle, LabelsAreEscaped) {
  const std::string nasty = "a \"quoted\" back\\slash,\nnew line\ttab \xc3\xa9 '; . #";
  // the same text as a JSON string
  const std::string json = R"("a \"quoted\" back\\slash,\nnew line\ttab \u00e9 '; . #")";
  const Scene s = scene_of(json, "[" + kTable + "]",
                           R"([{"name": )" + json + R"(, "type": "Cylinder", "shape": "cylinder", "radius": 0.02,
                                "height": 0.1, "mass": 0.3, "on": "table"}])",
                           R"(, "gripper": )" + json + R"(, "arm": "\\")");
  ASSERT_EQ(s.name, nasty);
  const std::string turtle = to_turtle(s);
  ASSERT_EQ(turtle.find('\n'), turtle.find("regenerate.\n") + 11) << "the comment line must stay one line";
  Graph g = read_back(turtle);
  EXPECT_EQ(g["skiros:Scene-0"]["rdfs:label"], std::vector<std::string>{nasty});
  EXPECT_EQ(g["skiros:Cylinder-2"]["rdfs:label"], std::vector<std::string>{nasty});
  EXPECT_EQ(g["skiros:Cylinder-2"]["skiros:Size"], std::vector<std::string>{"0.04"});  // the diameter
  EXPECT_EQ(g["skiros:Cylinder-2"]["skiros:Weight"], std::vector<std::string>{"0.3"});
  EXPECT_EQ(g["skiros:Gripper-4"]["rdfs:label"], std::vector<std::string>{nasty});
  EXPECT_EQ(g["skiros:Arm-5"]["rdfs:label"], std::vector<std::string>{"\\"});

  // quotes and backslashes at the ends, three quotes in a row, carriage returns, nothing
  Scene t = scene_of(R"("t")", "[]", "[]");
  for (const std::string label : {"\"", "end\"", "\"start", "a\"\"\"b", "x\n\"", "\\", "x\\", "\r\n", "", "\"\"\"\"",
                                  "tab\there"}) {
    t.name = label;
    EXPECT_EQ(read_back(to_turtle(t))["skiros:Scene-0"]["rdfs:label"], std::vector<std::string>{label}) << label;
  }
}

TEST(SceneTurtle, NumbersAreRoundedToSixDecimalsInShortestForm) {
  EXPECT_EQ(turtle_number(0.5), "0.5");
  EXPECT_EQ(turtle_number(1.0), "1");
  EXPECT_EQ(turtle_number(0.4 - 0.5), "-0.1");  // -0.09999999999999998
  EXPECT_EQ(turtle_number(0.1 + 0.2), "0.3");
  EXPECT_EQ(turtle_number(0.70710678118), "0.707107");
  EXPECT_EQ(turtle_number(-1e-9), "0");  // not -0
  EXPECT_EQ(turtle_number(1e-6), "1e-06");
  EXPECT_EQ(turtle_number(123456.0000004), "123456");
}

TEST(SceneTurtle, PosesBecomeRelativeToATurnedFixture) {
  // a table turned 90 degrees about z at (1, 0, 0); an object 0.2 m further along world y
  const double r = std::sqrt(0.5);
  const Pose p = relative_pose({1, 0, 0, 0, 0, r, r}, {1, 0.2, 0.5, 0, 0, 0, 1});
  EXPECT_NEAR(p[0], 0.2, 1e-12);  // world +y is the table's +x
  EXPECT_NEAR(p[1], 0.0, 1e-12);
  EXPECT_NEAR(p[2], 0.5, 1e-12);
  EXPECT_NEAR(p[5], -r, 1e-12);  // and the object is turned back
  EXPECT_NEAR(p[6], r, 1e-12);
}

TEST(SceneTurtle, TheNormalizedJsonReadsBackTheSame) {
  const Scene s = load_scene(kDir + "/demo.scene.json");
  const std::string once = to_json(s);
  const Scene again = parse_scene(once, "");
  EXPECT_EQ(to_json(again), once);
  EXPECT_EQ(to_turtle(again), to_turtle(s));
  EXPECT_NE(once.find(R"("arm":"arm","gripper":"gripper")"), std::string::npos) << once;
}

TEST(SceneTurtle, ATypeMustBeAConceptName) {
  try {
    scene_of(R"("t")", "[]", R"([{"name": "c", "type": "Big Box", "shape": "box", "size": [1, 1, 1]}])");
    FAIL() << "a type with a space was accepted";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("objects[0].type must be a concept name"), std::string::npos) << e.what();
  }
  const Scene s = scene_of(R"("t")", R"([{"name": "f", "urdf": "../../sim_server/models/table.urdf"}])",
                           R"([{"name": "c", "shape": "box", "size": [1, 1, 1]}])");
  EXPECT_EQ(s.fixtures[0].type, "Location");  // the defaults of docs/scene.md
  EXPECT_EQ(s.objects[0].type, "Product");
}

TEST(SceneTurtle, ArticulatedObjectsAndTheirPartsComeLast) {
  // An obstacle and a cabinet: the robot's ids stay, the obstacle follows the robot, the
  // cabinet and its parts (by joint name) come after everything.
  const std::string text = R"({"name": "t",
    "robot": {"name": "r", "urdf": "../../sim_server/models/arm6.urdf", "tool_link": "link6",
              "left_finger_joint": "finger_left_joint", "right_finger_joint": "finger_right_joint"},
    "fixtures": [)" + kTable + R"(],
    "obstacles": [{"name": "post", "urdf": "../../sim_server/models/post.urdf", "pose": [0.3, 0.5, 0, 0, 0, 0, 1]}],
    "objects": [)" + cube("a", "table") + R"(],
    "articulated": [{"name": "cab", "type": "Cabinet", "urdf": "../../sim_server/models/cabinet.urdf",
                     "pose": [0, -0.55, 0, 0, 0, 0.7071067811865476, 0.7071067811865476],
                     "initial_joints": {"door_joint": 0.5},
                     "joints": {"drawer_joint": {"type": "Drawer"}, "door_joint": {"type": "Door", "handle": [0, 0, 0, 0, 0, 0, 1]}}}]})";
  const Scene s = parse_scene(text, kDir + "/test.scene.json");
  std::vector<std::string> ids, labels, parents;
  for (const auto& e : world_elements(s)) {
    ids.push_back(e.id);
    labels.push_back(e.label);
    parents.push_back(e.parent);
  }
  EXPECT_EQ(ids, (std::vector<std::string>{"Table-1", "Cube-2", "Robot-3", "Gripper-4", "Arm-5", "Obstacle-6", "Cabinet-7",
                                           "Door-8", "Drawer-9"}));
  EXPECT_EQ(labels, (std::vector<std::string>{"table", "a", "r", "gripper", "arm", "post", "cab", "cab/door_joint",
                                              "cab/drawer_joint"}));
  EXPECT_EQ(parents[7], "Cabinet-7");
  EXPECT_EQ(parents[8], "Cabinet-7");

  Graph g = read_back(to_turtle(s));
  EXPECT_EQ(g["skiros:Scene-0"]["skiros:contain"],
            (std::vector<std::string>{"skiros:Table-1", "skiros:Robot-3", "skiros:Obstacle-6", "skiros:Cabinet-7"}));
  EXPECT_EQ(g["skiros:Cabinet-7"]["skiros:contain"], (std::vector<std::string>{"skiros:Door-8", "skiros:Drawer-9"}));
  EXPECT_EQ(g["skiros:Cabinet-7"]["rdf:type"], (std::vector<std::string>{"skiros:Cabinet", "owl:NamedIndividual"}));
  EXPECT_EQ(g["skiros:Cabinet-7"]["skiros:PositionY"], std::vector<std::string>{"-0.55"});  // its world pose, as a fixture's
  EXPECT_EQ(g["skiros:Cabinet-7"]["skiros:OrientationZ"], std::vector<std::string>{"0.707107"});
  EXPECT_EQ(g["skiros:Door-8"]["rdf:type"], (std::vector<std::string>{"skiros:Door", "owl:NamedIndividual"}));
  EXPECT_EQ(g["skiros:Door-8"]["rdfs:label"], std::vector<std::string>{"cab/door_joint"});
  EXPECT_EQ(g["skiros:Door-8"]["skiros:JointName"], std::vector<std::string>{"door_joint"});
  EXPECT_EQ(g["skiros:Door-8"]["skiros:JointPosition"], std::vector<std::string>{"0.5"});
  EXPECT_EQ(g["skiros:Drawer-9"]["skiros:JointPosition"], std::vector<std::string>{"0"});  // not given: 0
  EXPECT_EQ(g["skiros:Drawer-9"].count("skiros:PositionX"), 0u);  // no pose: it moves with the joint
  EXPECT_EQ(g["skiros:Drawer-9"].count("skiros:contain"), 0u);

  // The committed cabinet scene's ids.
  std::vector<std::string> cabinet;
  for (const auto& e : world_elements(load_scene(kDir + "/cabinet.scene.json"))) cabinet.push_back(e.id + " " + e.label);
  EXPECT_EQ(cabinet, (std::vector<std::string>{"Table-1 table", "Cube-2 red", "Cube-3 green", "Robot-4 arm_robot",
                                               "Gripper-5 gripper", "Arm-6 arm", "Cabinet-7 cabinet",
                                               "Door-8 cabinet/door_joint", "Drawer-9 cabinet/drawer_joint"}));
}

// The world model takes the cabinet scene's Turtle with its ontology: the concepts and
// data properties are declared, and a part may contain what lies in it.
TEST(SceneTurtle, TheWorldModelLoadsTheCabinetScene) {
  std::ifstream f(SKILLBUS_TEST_ONTOLOGY);
  ASSERT_TRUE(f) << SKILLBUS_TEST_ONTOLOGY;
  wm::Ontology onto;
  wm::Prefixes px;
  onto.load_turtle(std::string(std::istreambuf_iterator<char>(f), {}), px, "skiros.ttl");
  EXPECT_TRUE(onto.is_subclass("skiros:Cabinet", "skiros:ArticulatedObject"));
  EXPECT_TRUE(onto.is_subclass("skiros:Cabinet", "skiros:Location"));
  EXPECT_TRUE(onto.is_subclass("skiros:Drawer", "skiros:ArticulatedPart"));
  EXPECT_TRUE(onto.is_subclass("skiros:Door", "skiros:Location"));
  EXPECT_FALSE(onto.is_subclass("skiros:Door", "skiros:Product"));
  EXPECT_TRUE(onto.may_relate("skiros:Drawer", "skiros:contain", "skiros:Cube"));
  EXPECT_TRUE(onto.may_relate("skiros:Cabinet", "skiros:contain", "skiros:Drawer"));

  const wm::Scene scene = wm::read_scene(to_turtle(load_scene(kDir + "/cabinet.scene.json")), onto, px, "cabinet.ttl");
  wm::check_scene_types(scene, onto, "cabinet.ttl");
  wm::WorldStore store(onto);
  std::vector<wm::Op> ops;
  for (const auto& e : scene.elements) ops.push_back(wm::Op{wm::Op::AddElement, e, {}});
  for (const auto& r : scene.relations) ops.push_back(wm::Op{wm::Op::AddRelation, {}, r});
  ASSERT_NO_THROW(store.apply(ops));
  const wm::Element* d = store.get("skiros:Drawer-9");
  ASSERT_NE(d, nullptr);
  EXPECT_EQ(d->label, "cabinet/drawer_joint");
  EXPECT_EQ(d->properties.at("skiros:JointPosition")[0], wm::Value(0.0));
  EXPECT_EQ(d->properties.at("skiros:JointName")[0], wm::Value(std::string("drawer_joint")));
  // A cube moved from the table into the drawer.
  EXPECT_NO_THROW(store.apply({wm::Op{wm::Op::RemoveRelation, {}, wm::Relation{"skiros:Table-1", "skiros:contain", "skiros:Cube-2"}},
                               wm::Op{wm::Op::AddRelation, {}, wm::Relation{"skiros:Drawer-9", "skiros:contain", "skiros:Cube-2"}}}));
}

// deploy/scenes/cabinet.ttl is generated from cabinet.scene.json (`skillbus scene turtle
// deploy/scenes/cabinet.scene.json -o deploy/scenes/cabinet.ttl`): regenerate it when the
// scene changes.
TEST(SceneTurtle, TheCommittedCabinetTurtleIsUpToDate) {
  std::ifstream f(kDir + "/cabinet.ttl");
  ASSERT_TRUE(f);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(f), {}), to_turtle(load_scene(kDir + "/cabinet.scene.json")));
}
