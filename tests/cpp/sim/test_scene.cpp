// Scene files: the demo scene loads; every kind of mistake is named with its field.
#include <gtest/gtest.h>

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
  ASSERT_EQ(s.fixtures.size(), 2u);
  EXPECT_EQ(s.physics.collision_detector, "bullet");
  EXPECT_EQ(s.robot.tool_link, "link6");
  EXPECT_NE(s.robot.urdf.find("sim_server/models/arm6.urdf"), std::string::npos);
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
