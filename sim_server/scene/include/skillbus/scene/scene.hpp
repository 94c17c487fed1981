// The scene file: one JSON document that lists the robot(s), the fixtures (table, bin) and
// the graspable objects with their poses. The physics server builds its world from it,
// and `skillbus scene turtle` turns the same file into the world model's Turtle scene,
// so belief and truth start from one source. Format: docs/scene.md. The physics server
// (sim_server) and the motion server (motion_server) both read it with this library.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace skillbus::scene {

// x y z qx qy qz qw, world frame.
using Pose = std::array<double, 7>;

class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct RobotSpec {
  std::string name;
  std::string urdf;                         // absolute path (resolved against the scene file)
  Pose pose{0, 0, 0, 0, 0, 0, 1};
  std::map<std::string, double> initial_joints;
  std::string tool_link;                    // the link the tool centre point hangs on
  double tool_offset = 0.0;                 // m along that link's z axis
  std::string left_finger_joint, right_finger_joint;
  std::string arm = "arm", gripper = "gripper";  // labels of the world model's Arm and Gripper
  // The robot's bus namespace: its processes run with `--robot <bus_name>` and its
  // channels are "<bus_name>/SB_ROBOT_..." (docs/transport.md, "Several robots"). Empty
  // for the one robot of a scene's "robot" field; the robot's name in a "robots" list.
  std::string bus_name;
};

struct FixtureSpec {
  std::string name;
  std::string type = "Location";            // the world model's concept, without "skiros:"
  std::string urdf;
  Pose pose{0, 0, 0, 0, 0, 0, 1};
  double friction = 0.8;
  // From the scene's "obstacles" list: a fixture in the way of the arm (a post, a wall)
  // that no object starts on. The physics counts the steps in which a robot touches one;
  // its world-model id comes after the robots' so that adding one renumbers nothing.
  bool obstacle = false;
};

struct ObjectSpec {
  std::string name;
  std::string type = "Product";             // the world model's concept, without "skiros:"
  std::string shape;                        // "box" or "cylinder"
  std::array<double, 3> size{0, 0, 0};      // box: x y z; cylinder: radius, height, 0
  double mass = 0.1;                        // kg
  double friction = 0.8;
  Pose pose{0, 0, 0, 0, 0, 0, 1};
  std::string on;                           // the fixture it starts on (world model containment)
};

// One joint of an articulated object that the scene names (a drawer's slide, a door's
// hinge): its world-model concept, the dynamics that override the URDF's, and where the
// tool grasps its handle.
struct ArticulatedJointSpec {
  std::string type = "ArticulatedPart";     // the world model's concept, without "skiros:"
  std::optional<double> damping, friction;  // override the URDF's <dynamics> when given
  std::optional<Pose> handle;               // the tool centre point's grasp pose in the joint's child link frame
};

// An articulated object (a cabinet with a drawer and a door): a URDF whose root link is
// fixed at `pose` and whose joints move (passive, damped, within their limits).
struct ArticulatedSpec {
  std::string name;
  std::string type = "ArticulatedObject";   // the world model's concept, without "skiros:"
  std::string urdf;
  Pose pose{0, 0, 0, 0, 0, 0, 1};
  double friction = 0.8;                    // of every shape of the URDF
  std::map<std::string, double> initial_joints;
  std::map<std::string, ArticulatedJointSpec> joints;  // by joint name (sorted): never empty
};

// A simulated depth camera (docs/scene.md, "Cameras"). Its frame is the optical frame:
// z along the view, x to the right of the image, y down it. Fixed in the world (`pose` in
// the world frame), or mounted on a robot's link (`robot` and `link`; `pose` relative to
// that link) and moving with it.
struct CameraSpec {
  std::string name;
  std::string robot, link;                  // both empty: fixed in the world
  Pose pose{0, 0, 0, 0, 0, 0, 1};
  int width = 160, height = 120;            // pixels
  double fx = 0, fy = 0, cx = 0, cy = 0;    // pixels (from fov_deg unless given as intrinsics)
  double near = 0.05, far = 3.0;            // m: returns outside [near, far] are no return
  double rate_hz = 0;                       // captures per second of sim time; 0: on request only
  double noise_stddev_m = 0;                // Gaussian noise along each ray (m); 0: exact
  uint64_t seed = 1;                        // of the noise: the same seed gives the same clouds
};

struct PhysicsSpec {
  double step_ms = 2.0;   // the default: see docs/sim_server.md, "Choosing the step"
  double frame_ms = 10.0;
  std::array<double, 3> gravity{0, 0, -9.81};
  std::string collision_detector = "bullet";  // bullet | dart | fcl
  std::string lcp_solver = "dantzig";         // dantzig (PGS as fallback) | pgs
};

struct Scene {
  std::string path;  // the file it came from
  std::string name;
  PhysicsSpec physics;
  std::vector<RobotSpec> robots;  // at least one; names, arm and gripper labels all distinct
  std::vector<FixtureSpec> fixtures;
  std::vector<ObjectSpec> objects;
  std::vector<CameraSpec> cameras;
  std::vector<ArticulatedSpec> articulated;
};

// The robot whose bus name is `bus_name` ("" for the one robot of a "robot" scene);
// throws SceneError naming the robots there are.
const RobotSpec& robot_on_bus(const Scene& scene, const std::string& bus_name);

// Reads and checks a scene file. Throws SceneError naming the file and the offending
// field (e.g. "scene.json: objects[1].mass must be > 0").
Scene load_scene(const std::string& path);
// `path` names the file in messages and is the folder relative URDF paths start from
// ("": "<scene>" in messages, the current folder).
Scene parse_scene(const std::string& json_text, const std::string& path);

// The scene as a scene file again, normalized: every default filled in, URDF paths
// absolute, quaternions unit (what `sb_scene check --json` prints). Reading it back gives
// the same Scene. indent < 0: one line.
std::string to_json(const Scene& scene, int indent = -1);

}  // namespace skillbus::scene
