#include "skillbus/scene/scene.hpp"

#include <cctype>
#include <cmath>
#include <random>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "skillbus/bus.hpp"

namespace skillbus::scene {

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

// Reads fields of one JSON object and names the offending field in every error.
class Reader {
 public:
  Reader(const json& j, std::string where, std::string file) : j_(j), where_(std::move(where)), file_(std::move(file)) {
    if (!j_.is_object()) fail("must be an object");
  }

  [[noreturn]] void fail(const std::string& what) const { throw SceneError(file_ + ": " + where_ + " " + what); }
  [[noreturn]] void fail_field(const std::string& key, const std::string& what) const {
    throw SceneError(file_ + ": " + field(key) + " " + what);
  }
  std::string field(const std::string& key) const { return where_.empty() ? key : where_ + "." + key; }
  bool has(const std::string& key) const { return j_.contains(key); }
  const std::string& file() const { return file_; }

  std::string str(const std::string& key, const std::string& def, bool required = false) const {
    if (!has(key)) {
      if (required) fail_field(key, "is missing");
      return def;
    }
    if (!j_[key].is_string()) fail_field(key, "must be a string");
    const std::string s = j_[key].get<std::string>();
    if (required && s.empty()) fail_field(key, "must not be empty");
    return s;
  }
  double num(const std::string& key, double def) const {
    if (!has(key)) return def;
    if (!j_[key].is_number()) fail_field(key, "must be a number");
    const double v = j_[key].get<double>();
    if (!std::isfinite(v)) fail_field(key, "must be finite");
    return v;
  }
  template <size_t N>
  std::array<double, N> vec(const std::string& key, std::array<double, N> def, bool required = false) const {
    if (!has(key)) {
      if (required) fail_field(key, "is missing");
      return def;
    }
    const json& a = j_[key];
    if (!a.is_array() || a.size() != N) fail_field(key, "must be an array of " + std::to_string(N) + " numbers");
    std::array<double, N> out{};
    for (size_t i = 0; i < N; ++i) {
      if (!a[i].is_number()) fail_field(key, "[" + std::to_string(i) + "] must be a number");
      out[i] = a[i].get<double>();
      if (!std::isfinite(out[i])) fail_field(key, "[" + std::to_string(i) + "] must be finite");
    }
    return out;
  }
  Pose pose(const std::string& key) const {
    Pose p = vec<7>(key, Pose{0, 0, 0, 0, 0, 0, 1});
    const double n = std::sqrt(p[3] * p[3] + p[4] * p[4] + p[5] * p[5] + p[6] * p[6]);
    if (n < 1e-9) fail_field(key, "has a zero quaternion (x y z qx qy qz qw)");
    for (int i = 3; i < 7; ++i) p[i] /= n;
    return p;
  }
  const json& sub(const std::string& key) const { return j_[key]; }

 private:
  const json& j_;
  std::string where_, file_;
};

// A uniform double in [0, 1) from the top 53 bits: std::mt19937_64's sequence is fixed by
// the standard, std::uniform_real_distribution's mapping is not (the same seed would give
// other poses on another standard library).
double unit(std::mt19937_64& g) { return static_cast<double>(g() >> 11) * 0x1.0p-53; }

// "scatter": the objects on one fixture at seeded-random places of a region (world x, y),
// turned by a random yaw, no two centres closer than min_gap. Applied when the scene is
// read, so the physics server and the world model's Turtle see the same poses.
void scatter(const Reader& r, Scene& s) {
  const std::string on = r.str("on", "", true);
  bool found = false;
  for (const auto& f : s.fixtures) found = found || (f.name == on && !f.obstacle);
  if (!found) r.fail_field("on", "names '" + on + "', which is not a fixture");
  const double seed = r.num("seed", 0);
  if (seed < 0 || seed != std::floor(seed) || seed > 4294967295.0) r.fail_field("seed", "must be a whole number from 0 to 4294967295");
  const auto region = r.vec<4>("region", {}, true);  // x_min y_min x_max y_max
  if (!(region[2] > region[0] && region[3] > region[1])) r.fail_field("region", "must be [x_min, y_min, x_max, y_max] with max > min");
  const double gap = r.num("min_gap", 0.1);
  if (gap < 0) r.fail_field("min_gap", "must be >= 0");
  bool turn = true;  // a random yaw too
  if (r.has("yaw")) {
    if (!r.sub("yaw").is_boolean()) r.fail_field("yaw", "must be true or false");
    turn = r.sub("yaw").get<bool>();
  }
  std::mt19937_64 g(static_cast<uint64_t>(seed));
  constexpr int kTries = 1000;  // per object
  std::vector<std::array<double, 2>> placed;
  for (auto& o : s.objects) {
    if (o.on != on) continue;
    int tries = 0;
    std::array<double, 2> xy{};
    bool clear = false;
    while (!clear && tries++ < kTries) {
      xy = {region[0] + unit(g) * (region[2] - region[0]), region[1] + unit(g) * (region[3] - region[1])};
      clear = true;
      for (const auto& p : placed) clear = clear && std::hypot(p[0] - xy[0], p[1] - xy[1]) >= gap;
    }
    if (!clear)
      r.fail("cannot place " + std::to_string(placed.size() + 1) + " objects " + std::to_string(gap) +
             " m apart in its region (a larger region or a smaller min_gap)");
    placed.push_back(xy);
    const double yaw = turn ? (unit(g) * 2 - 1) * M_PI : 0.0;
    o.pose[0] = xy[0];
    o.pose[1] = xy[1];
    // yaw about the world's z, then the object's own orientation
    const double cz = std::cos(yaw / 2), sz = std::sin(yaw / 2);
    const double x = o.pose[3], y = o.pose[4], z = o.pose[5], w = o.pose[6];
    o.pose[3] = cz * x - sz * y;
    o.pose[4] = cz * y + sz * x;
    o.pose[5] = cz * z + sz * w;
    o.pose[6] = cz * w - sz * z;
  }
}

std::string resolve(const std::string& base_dir, const std::string& p) {
  fs::path q(p);
  if (q.is_relative()) q = fs::path(base_dir) / q;
  return fs::weakly_canonical(q).string();
}

void check_file(const Reader& r, const std::string& key, const std::string& path) {
  if (!fs::is_regular_file(path)) r.fail_field(key, "names a file that does not exist: " + path);
}

// A concept of the world model's ontology without "skiros:" (it becomes part of an IRI,
// skiros:<type>-<n>): a letter, then letters, digits or _.
std::string concept_type(const Reader& r, const std::string& def) {
  const std::string t = r.str("type", def);
  bool ok = !t.empty() && std::isalpha(static_cast<unsigned char>(t[0]));
  for (char c : t) ok = ok && (std::isalnum(static_cast<unsigned char>(c)) || c == '_');
  if (!ok) r.fail_field("type", "must be a concept name (a letter, then letters, digits or _), not '" + t + "'");
  return t;
}

// "initial_joints": {joint: position} (the physics server checks the names and limits
// against the URDF).
std::map<std::string, double> initial_joints(const Reader& r) {
  std::map<std::string, double> out;
  if (!r.has("initial_joints")) return out;
  const json& ij = r.sub("initial_joints");
  if (!ij.is_object()) r.fail_field("initial_joints", "must be an object {joint: position}");
  for (auto it = ij.begin(); it != ij.end(); ++it) {
    if (!it.value().is_number() || !std::isfinite(it.value().get<double>()))
      r.fail_field("initial_joints." + it.key(), "must be a finite number");
    out[it.key()] = it.value().get<double>();
  }
  return out;
}

// An articulated object's "joints": {joint: {type, damping, friction, handle}}, at least
// one (the joints the physics reports and the world model knows; the physics checks that
// each is a 1-DoF prismatic or revolute joint of the URDF).
void read_joints(const Reader& r, ArticulatedSpec& a) {
  if (!r.has("joints")) r.fail_field("joints", "is missing");
  const json& js = r.sub("joints");
  if (!js.is_object() || js.empty()) r.fail_field("joints", "must be a non-empty object {joint: {...}}");
  for (auto it = js.begin(); it != js.end(); ++it) {
    if (it.key().empty()) r.fail_field("joints", "names a joint with an empty name");
    Reader j(it.value(), r.field("joints." + it.key()), r.file());
    ArticulatedJointSpec spec;
    spec.type = concept_type(j, spec.type);
    if (j.has("damping")) spec.damping = j.num("damping", 0);
    if (j.has("friction")) spec.friction = j.num("friction", 0);
    if (spec.damping && *spec.damping < 0) j.fail_field("damping", "must be >= 0");
    if (spec.friction && *spec.friction < 0) j.fail_field("friction", "must be >= 0");
    if (j.has("handle")) spec.handle = j.pose("handle");
    a.joints[it.key()] = spec;
  }
}

// The largest image a capture may have: every pixel is a ray cast, and the cloud is
// published whole in one frame.
constexpr int kMaxPixels = 1 << 20;

void read_intrinsics(const Reader& r, CameraSpec& c) {
  if (r.has("intrinsics") && r.has("fov_deg")) r.fail_field("fov_deg", "and intrinsics both given: give one");
  if (r.has("intrinsics")) {
    const auto k = r.vec<4>("intrinsics", {});
    c.fx = k[0], c.fy = k[1], c.cx = k[2], c.cy = k[3];
    if (c.fx <= 0 || c.fy <= 0) r.fail_field("intrinsics", "must have fx > 0 and fy > 0 ([fx, fy, cx, cy], pixels)");
    return;
  }
  // The vertical field of view; square pixels, the principal point at the image's centre.
  const double fov = r.num("fov_deg", 60.0);
  if (fov <= 0 || fov >= 180) r.fail_field("fov_deg", "must be between 0 and 180 (exclusive)");
  c.fy = c.fx = 0.5 * c.height / std::tan(0.5 * fov * M_PI / 180.0);
  c.cx = 0.5 * c.width;
  c.cy = 0.5 * c.height;
}

void read_cameras(const Reader& top, Scene& s, const std::string& file) {
  const json& arr = top.sub("cameras");
  if (!arr.is_array()) top.fail_field("cameras", "must be an array");
  std::set<std::string> names;
  for (size_t i = 0; i < arr.size(); ++i) {
    Reader r(arr[i], "cameras[" + std::to_string(i) + "]", file);
    CameraSpec c;
    c.name = r.str("name", "", true);
    if (!valid_robot_name(c.name))  // (it is written in messages and on the command line)
      r.fail_field("name", "'" + c.name + "' must be a letter then letters, digits or _");
    if (!names.insert(c.name).second) r.fail_field("name", "'" + c.name + "' is used twice among the cameras");
    c.robot = r.str("robot", "");
    c.link = r.str("link", "");
    if (c.robot.empty() != c.link.empty())
      r.fail_field(c.robot.empty() ? "link" : "robot", "needs robot and link both (a camera mounted on a robot's link)");
    if (!c.robot.empty()) {
      bool found = false;
      for (const auto& robot : s.robots) found = found || robot.name == c.robot;
      if (!found) r.fail_field("robot", "names '" + c.robot + "', which is not a robot of the scene");
    }
    c.pose = r.pose("pose");
    const double w = r.num("width", 160), h = r.num("height", 120);
    if (w < 1 || h < 1 || w != std::floor(w) || h != std::floor(h))
      r.fail_field(w < 1 || w != std::floor(w) ? "width" : "height", "must be a whole number of pixels >= 1");
    if (w * h > kMaxPixels) r.fail_field("width", "times height must be at most " + std::to_string(kMaxPixels));
    c.width = static_cast<int>(w);
    c.height = static_cast<int>(h);
    read_intrinsics(r, c);
    c.near = r.num("near", c.near);
    c.far = r.num("far", c.far);
    if (c.near <= 0) r.fail_field("near", "must be > 0 (m)");
    if (c.far <= c.near) r.fail_field("far", "must be > near (m)");
    c.rate_hz = r.num("rate_hz", 0);
    if (c.rate_hz < 0) r.fail_field("rate_hz", "must be >= 0 (0: on request only)");
    c.noise_stddev_m = r.num("noise_stddev_m", 0);
    if (c.noise_stddev_m < 0) r.fail_field("noise_stddev_m", "must be >= 0");
    const double seed = r.num("seed", 1);
    if (seed < 0 || seed != std::floor(seed) || seed > 9007199254740992.0)
      r.fail_field("seed", "must be a whole number >= 0");
    c.seed = static_cast<uint64_t>(seed);
    s.cameras.push_back(c);
  }
}

}  // namespace

Scene parse_scene(const std::string& text, const std::string& path) {
  const std::string file = path.empty() ? "<scene>" : path;
  json root;
  try {
    root = json::parse(text);
  } catch (const json::parse_error& e) {
    throw SceneError(file + ": not valid JSON: " + e.what());
  }
  const std::string base = path.empty() ? "." : fs::path(path).parent_path().string();
  Reader top(root, "", file);
  Scene s;
  s.path = path;
  s.name = top.str("name", "scene");

  if (top.has("physics")) {
    Reader p(top.sub("physics"), "physics", file);
    s.physics.step_ms = p.num("step_ms", 2.0);
    s.physics.frame_ms = p.num("frame_ms", 10.0);
    s.physics.gravity = p.vec<3>("gravity", s.physics.gravity);
    s.physics.collision_detector = p.str("collision_detector", "bullet");
    s.physics.lcp_solver = p.str("lcp_solver", "dantzig");
    if (s.physics.lcp_solver != "dantzig" && s.physics.lcp_solver != "pgs")
      p.fail_field("lcp_solver", "must be dantzig or pgs");
    if (s.physics.step_ms <= 0) p.fail_field("step_ms", "must be > 0");
    if (s.physics.frame_ms < s.physics.step_ms) p.fail_field("frame_ms", "must be >= step_ms");
    const double ratio = s.physics.frame_ms / s.physics.step_ms;
    if (std::abs(ratio - std::round(ratio)) > 1e-9) p.fail_field("frame_ms", "must be a whole number of steps");
    const std::set<std::string> detectors{"bullet", "dart", "fcl"};
    if (!detectors.count(s.physics.collision_detector))
      p.fail_field("collision_detector", "must be one of bullet, dart, fcl");
  }

  // One robot ("robot": {...}, on the bus without a namespace) or several ("robots":
  // [...], each on the bus under its name).
  if (top.has("robot") == top.has("robots"))
    throw SceneError(file + ": " + (top.has("robot") ? std::string("give either robot or robots, not both")
                                                     : std::string("robot is missing (or robots, for several)")));
  auto read_robot = [&](const json& j, const std::string& where) {
    Reader r(j, where, file);
    RobotSpec robot;
    robot.name = r.str("name", "robot", true);
    robot.urdf = resolve(base, r.str("urdf", "", true));
    check_file(r, "urdf", robot.urdf);
    robot.pose = r.pose("pose");
    robot.tool_link = r.str("tool_link", "", true);
    robot.tool_offset = r.num("tool_offset", 0.0);
    robot.left_finger_joint = r.str("left_finger_joint", "", true);
    robot.right_finger_joint = r.str("right_finger_joint", "", true);
    robot.arm = r.str("arm", "arm");
    robot.gripper = r.str("gripper", "gripper");
    robot.initial_joints = initial_joints(r);
    return robot;
  };
  if (top.has("robot")) {
    s.robots.push_back(read_robot(top.sub("robot"), "robot"));
  } else {
    const json& arr = top.sub("robots");
    if (!arr.is_array() || arr.empty()) top.fail_field("robots", "must be a non-empty array");
    for (size_t i = 0; i < arr.size(); ++i) {
      const std::string where = "robots[" + std::to_string(i) + "]";
      RobotSpec robot = read_robot(arr[i], where);
      // The name is a bus namespace: channel and DDS topic names take it as it is.
      if (!valid_robot_name(robot.name))  // (the bus's rule: skillbus/bus.hpp)
        throw SceneError(file + ": " + where + ".name '" + robot.name +
                         "' must be a letter then letters, digits or _ (it names the robot's channels)");
      robot.bus_name = robot.name;
      s.robots.push_back(std::move(robot));
    }
  }

  std::set<std::string> names, robot_labels;
  for (size_t i = 0; i < s.robots.size(); ++i) {
    const RobotSpec& r = s.robots[i];
    const std::string where = top.has("robot") ? "robot" : "robots[" + std::to_string(i) + "]";
    if (!names.insert(r.name).second) throw SceneError(file + ": " + where + ".name '" + r.name + "' is used twice in the scene");
    // The robots' arm and gripper labels: the physics reports an object held by naming its
    // gripper's label, which must say which robot holds it.
    for (const std::string* label : {&r.arm, &r.gripper})
      if (!robot_labels.insert(*label).second)
        throw SceneError(file + ": " + where + (label == &r.arm ? ".arm" : ".gripper") + " '" + *label +
                         "' is used twice among the robots");
  }
  auto unique_name = [&](const Reader& r, const std::string& n) {
    if (!names.insert(n).second) r.fail_field("name", "'" + n + "' is used twice in the scene");
  };
  // Fixtures, then obstacles: both fixed bodies from a URDF, read alike.
  for (const char* list : {"fixtures", "obstacles"}) {
    if (!top.has(list)) continue;
    const bool obstacle = std::string(list) == "obstacles";
    const json& arr = top.sub(list);
    if (!arr.is_array()) top.fail_field(list, "must be an array");
    for (size_t i = 0; i < arr.size(); ++i) {
      Reader r(arr[i], std::string(list) + "[" + std::to_string(i) + "]", file);
      FixtureSpec f;
      f.obstacle = obstacle;
      if (obstacle) f.type = "Obstacle";
      f.name = r.str("name", "", true);
      unique_name(r, f.name);
      f.type = concept_type(r, f.type);
      f.urdf = resolve(base, r.str("urdf", "", true));
      check_file(r, "urdf", f.urdf);
      f.pose = r.pose("pose");
      f.friction = r.num("friction", 0.8);
      if (f.friction < 0) r.fail_field("friction", "must be >= 0");
      s.fixtures.push_back(f);
    }
  }
  if (top.has("objects")) {
    const json& arr = top.sub("objects");
    if (!arr.is_array()) top.fail_field("objects", "must be an array");
    for (size_t i = 0; i < arr.size(); ++i) {
      Reader r(arr[i], "objects[" + std::to_string(i) + "]", file);
      ObjectSpec o;
      o.name = r.str("name", "", true);
      unique_name(r, o.name);
      o.type = concept_type(r, o.type);
      o.shape = r.str("shape", "", true);
      if (o.shape == "box") {
        o.size = r.vec<3>("size", {}, true);
      } else if (o.shape == "cylinder") {
        o.size[0] = r.num("radius", 0);
        o.size[1] = r.num("height", 0);
      } else {
        r.fail_field("shape", "must be \"box\" or \"cylinder\", not \"" + o.shape + "\"");
      }
      for (double d : o.size)
        if (d < 0) r.fail_field("size", "must not be negative");
      if (o.size[0] <= 0 || o.size[1] <= 0 || (o.shape == "box" && o.size[2] <= 0))
        r.fail_field(o.shape == "box" ? "size" : "radius/height", "must be > 0");
      o.mass = r.num("mass", 0.1);
      if (o.mass <= 0) r.fail_field("mass", "must be > 0");
      o.friction = r.num("friction", 0.8);
      if (o.friction < 0) r.fail_field("friction", "must be >= 0");
      o.pose = r.pose("pose");
      o.on = r.str("on", "");
      s.objects.push_back(o);
    }
    for (size_t i = 0; i < s.objects.size(); ++i) {
      const auto& o = s.objects[i];
      if (o.on.empty()) continue;
      bool found = false;
      for (const auto& f : s.fixtures) found = found || (f.name == o.on && !f.obstacle);
      if (!found)
        throw SceneError(file + ": objects[" + std::to_string(i) + "].on names '" + o.on +
                         "', which is not a fixture (objects do not start on obstacles)");
    }
  }
  if (top.has("articulated")) {
    const json& arr = top.sub("articulated");
    if (!arr.is_array()) top.fail_field("articulated", "must be an array");
    for (size_t i = 0; i < arr.size(); ++i) {
      Reader r(arr[i], "articulated[" + std::to_string(i) + "]", file);
      ArticulatedSpec a;
      a.name = r.str("name", "", true);
      unique_name(r, a.name);
      a.type = concept_type(r, a.type);
      a.urdf = resolve(base, r.str("urdf", "", true));
      check_file(r, "urdf", a.urdf);
      a.pose = r.pose("pose");
      a.friction = r.num("friction", 0.8);
      if (a.friction < 0) r.fail_field("friction", "must be >= 0");
      a.initial_joints = initial_joints(r);
      read_joints(r, a);
      s.articulated.push_back(std::move(a));
    }
  }
  if (top.has("cameras")) read_cameras(top, s, file);
  if (top.has("scatter")) scatter(Reader(top.sub("scatter"), "scatter", file), s);
  return s;
}

std::string to_json(const Scene& s, int indent) {
  using oj = nlohmann::ordered_json;
  auto pose = [](const Pose& p) { return oj(std::vector<double>(p.begin(), p.end())); };
  oj j;
  j["name"] = s.name;
  j["physics"] = {{"step_ms", s.physics.step_ms},
                  {"frame_ms", s.physics.frame_ms},
                  {"gravity", std::vector<double>(s.physics.gravity.begin(), s.physics.gravity.end())},
                  {"collision_detector", s.physics.collision_detector},
                  {"lcp_solver", s.physics.lcp_solver}};
  auto robot_json = [&](const RobotSpec& r) {
    oj joints = oj::object();
    for (const auto& [name, q] : r.initial_joints) joints[name] = q;
    return oj{{"name", r.name},
              {"urdf", r.urdf},
              {"pose", pose(r.pose)},
              {"tool_link", r.tool_link},
              {"tool_offset", r.tool_offset},
              {"left_finger_joint", r.left_finger_joint},
              {"right_finger_joint", r.right_finger_joint},
              {"initial_joints", joints},
              {"arm", r.arm},
              {"gripper", r.gripper}};
  };
  if (s.robots.size() == 1 && s.robots[0].bus_name.empty()) {
    j["robot"] = robot_json(s.robots[0]);
  } else {
    j["robots"] = oj::array();
    for (const auto& r : s.robots) j["robots"].push_back(robot_json(r));
  }
  j["fixtures"] = oj::array();
  for (const auto& f : s.fixtures)
    j[f.obstacle ? "obstacles" : "fixtures"].push_back(
        {{"name", f.name}, {"type", f.type}, {"urdf", f.urdf}, {"pose", pose(f.pose)}, {"friction", f.friction}});
  j["objects"] = oj::array();
  for (const auto& o : s.objects) {
    oj e = {{"name", o.name}, {"type", o.type}, {"shape", o.shape}};
    if (o.shape == "box") {
      e["size"] = std::vector<double>(o.size.begin(), o.size.end());
    } else {
      e["radius"] = o.size[0];
      e["height"] = o.size[1];
    }
    e["mass"] = o.mass;
    e["friction"] = o.friction;
    e["pose"] = pose(o.pose);
    if (!o.on.empty()) e["on"] = o.on;
    j["objects"].push_back(e);
  }
  if (!s.articulated.empty()) {  // (absent from a scene without: its normalized form stays as it was)
    j["articulated"] = oj::array();
    for (const auto& a : s.articulated) {
      oj initial = oj::object(), joints = oj::object();
      for (const auto& [name, q] : a.initial_joints) initial[name] = q;
      for (const auto& [name, spec] : a.joints) {
        oj e = {{"type", spec.type}};
        if (spec.damping) e["damping"] = *spec.damping;
        if (spec.friction) e["friction"] = *spec.friction;
        if (spec.handle) e["handle"] = pose(*spec.handle);
        joints[name] = e;
      }
      j["articulated"].push_back({{"name", a.name},
                                  {"type", a.type},
                                  {"urdf", a.urdf},
                                  {"pose", pose(a.pose)},
                                  {"friction", a.friction},
                                  {"initial_joints", initial},
                                  {"joints", joints}});
    }
  }
  if (!s.cameras.empty()) {
    j["cameras"] = oj::array();
    for (const auto& c : s.cameras) {
      oj e = {{"name", c.name}};
      if (!c.robot.empty()) e["robot"] = c.robot, e["link"] = c.link;
      e["pose"] = pose(c.pose);
      e["width"] = c.width;
      e["height"] = c.height;
      e["intrinsics"] = {c.fx, c.fy, c.cx, c.cy};
      e["near"] = c.near;
      e["far"] = c.far;
      e["rate_hz"] = c.rate_hz;
      e["noise_stddev_m"] = c.noise_stddev_m;
      e["seed"] = c.seed;
      j["cameras"].push_back(e);
    }
  }
  return j.dump(indent, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
}

const RobotSpec& robot_on_bus(const Scene& scene, const std::string& bus_name) {
  std::string known;
  for (const auto& r : scene.robots) {
    if (r.bus_name == bus_name) return r;
    known += (known.empty() ? "" : ", ") + (r.bus_name.empty() ? std::string("(none: the one robot)") : r.bus_name);
  }
  throw SceneError(scene.path + ": no robot '" + bus_name + "' (robots: " + known + ")");
}

Scene load_scene(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw SceneError(path + ": cannot open the scene file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_scene(ss.str(), path);
}

}  // namespace skillbus::scene
