// A scene file as the world model's Turtle scene (docs/scene.md, "From a scene file to the
// world model"): what `sb_scene turtle` and `skillbus scene turtle` write and
// `wm_server --scene` loads. The Turtle is written by the world model's own writer
// (skillbus::wm::write_turtle, on serd), so labels are escaped as Turtle requires.
#pragma once

#include <string>
#include <vector>

#include "skillbus/scene/scene.hpp"

namespace skillbus::scene {

// One element of the world model made from the scene, in the order of the ids.
struct WorldElement {
  enum Kind { Fixture, Object, Robot, Gripper, Arm, Articulated, ArticulatedPart };
  Kind kind = Fixture;
  std::string id;      // "Table-1" (without "skiros:")
  std::string type;    // "Table"
  std::string label;   // the name in the scene file
  std::string parent;  // the id of the element that contains it ("Scene-0" for the top level)
  Pose pose{0, 0, 0, 0, 0, 0, 1};  // relative to the parent
  const ObjectSpec* object = nullptr;  // for objects: the object (size and mass)
  // For an articulated object's part: the joint's name and initial position (m or rad).
  std::string joint;
  double joint_position = 0;
};

// The elements after Scene-0, numbered from 1 in the file's order: each fixture followed by
// the objects on it, then the objects on no fixture, then the robot, its gripper and its
// arm (Robot-n, Gripper-n+1, Arm-n+2; the gripper's and arm's parent is the robot, which
// has them, and their pose is the identity), then the obstacles, then each articulated
// object followed by its joints' parts in joint-name order (their parent is the object;
// they have no pose: it changes as the joint moves).
std::vector<WorldElement> world_elements(const Scene& scene);

// The world model's Turtle scene for `scene`: a comment line, the prefixes, then the
// triples (their order: Scene-0, then the elements in world_elements' order).
std::string to_turtle(const Scene& scene);

// child's pose in parent's frame (both x y z qx qy qz qw in the same frame); the same
// arithmetic, operation for operation, as skillbus.quat.relative in Python.
Pose relative_pose(const Pose& parent, const Pose& child);

// A number as the Turtle scene writes it: rounded to 6 decimals, then the shortest text
// that reads back as that double (std::to_chars), -0 as 0: 0.4999999 -> "0.5", 1.0 -> "1".
std::string turtle_number(double v);

}  // namespace skillbus::scene
