// The simulated depth camera against geometry computed by hand: a camera over the demo's
// table looks down on the table top (a plane) and a cube (a box); every pixel's range
// must match the analytic ray intersection to a fraction of a millimetre. Captures are
// the same bit for bit, noise is seeded, and capturing leaves the physics untouched.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <algorithm>
#include <cstring>
#include <limits>

#include "skillbus/scene/scene.hpp"
#include "skillbus/sim/physics.hpp"

using namespace skillbus;

namespace {
const std::string kDir = SKILLBUS_TEST_SCENE_DIR;  // deploy/scenes

// The table (top at z = 0.40 over x 0.2..0.8, y -0.4..0.4) and one 5 cm cube on it, and
// a camera 0.8 m over the table top looking straight down (optical z = world -z, y =
// world -y), whose view holds only the table and the cube, the cube's top and, the cube
// being off the axis, its side facing the camera.
std::string scene_text(const std::string& camera_extra = "", const std::string& cameras = "") {
  const std::string cams = cameras.empty() ? R"([{"name": "overhead", "pose": [0.5, 0, 1.2, 1, 0, 0, 0],
      "width": 48, "height": 64, "fov_deg": 40)" + camera_extra + "}]"
                                           : cameras;
  return R"({"name": "cam",
    "robot": {"name": "r", "urdf": "../../sim_server/models/arm6.urdf", "tool_link": "link6",
              "left_finger_joint": "finger_left_joint", "right_finger_joint": "finger_right_joint"},
    "fixtures": [{"name": "table", "urdf": "../../sim_server/models/table.urdf", "pose": [0.5, 0, 0, 0, 0, 0, 1]}],
    "objects": [{"name": "cube", "shape": "box", "size": [0.05, 0.05, 0.05], "pose": [0.5, 0.2, 0.425, 0, 0, 0, 1],
                 "on": "table"}],
    "cameras": )" + cams + "}";
}

scene::Scene make_scene(const std::string& extra = "", const std::string& cameras = "") {
  return scene::parse_scene(scene_text(extra, cameras), kDir + "/camera_test.scene.json");
}

// Distance along a unit ray to an axis-aligned box (slab method); infinity if missed.
double ray_box(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& lo,
               const Eigen::Vector3d& hi) {
  double t0 = 0, t1 = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-15) {
      if (o[k] < lo[k] || o[k] > hi[k]) return std::numeric_limits<double>::infinity();
      continue;
    }
    double a = (lo[k] - o[k]) / d[k], b = (hi[k] - o[k]) / d[k];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  return t0 <= t1 ? t0 : std::numeric_limits<double>::infinity();
}

Eigen::Isometry3d iso(const scene::Pose& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(p[0], p[1], p[2]);
  T.linear() = Eigen::Quaterniond(p[6], p[3], p[4], p[5]).toRotationMatrix();
  return T;
}

struct Compared {
  int pixels = 0, on_cube = 0, on_cube_side = 0;
  double worst = 0;  // m
};

// Every pixel against the table top, the cube and the floor (what the narrow view holds).
Compared compare(const sim::DepthCapture& c) {
  const Eigen::Isometry3d T = iso(c.pose);
  const Eigen::Vector3d table_lo(0.2, -0.4, 0.36), table_hi(0.8, 0.4, 0.40);
  const Eigen::Vector3d cube_lo(0.475, 0.175, 0.40), cube_hi(0.525, 0.225, 0.45);
  Compared out;
  for (int v = 0; v < c.height; ++v)
    for (int u = 0; u < c.width; ++u) {
      const size_t i = (static_cast<size_t>(v) * c.width + u) * 3;
      const Eigen::Vector3d dir =
          Eigen::Vector3d((u - c.intrinsics[2]) / c.intrinsics[0], (v - c.intrinsics[3]) / c.intrinsics[1], 1)
              .normalized();
      const Eigen::Vector3d o = T.translation(), d = T.linear() * dir;
      const double t_table = ray_box(o, d, table_lo, table_hi), t_cube = ray_box(o, d, cube_lo, cube_hi);
      const double expected = std::min(t_table, t_cube);
      EXPECT_TRUE(std::isfinite(expected)) << "pixel " << u << "," << v << " sees past the table";
      const Eigen::Vector3d p(c.xyz[i], c.xyz[i + 1], c.xyz[i + 2]);
      EXPECT_FALSE(std::isnan(p[0])) << "pixel " << u << "," << v << " has no return";
      if (std::isnan(p[0])) continue;
      // The point lies on its pixel's ray...
      EXPECT_LT((p.normalized() - dir).norm(), 1e-6) << "pixel " << u << "," << v;
      // ...at the analytic range.
      out.worst = std::max(out.worst, std::abs(p.norm() - expected));
      ++out.pixels;
      if (t_cube < t_table) {
        ++out.on_cube;
        const Eigen::Vector3d w = o + t_cube * d;
        if (w.z() < 0.4499) ++out.on_cube_side;
      }
    }
  return out;
}
}  // namespace

// (The issue asks for sub-millimetre; the exact intersection gives float32 rounding, about
// 20 nm here. Bullet's convex ray test, tried first, was 57 mm off at worst.)
TEST(DepthCamera, RangesMatchThePlaneAndTheBoxWithinAMicrometre) {
  sim::Physics physics(make_scene());
  ASSERT_EQ(physics.num_cameras(), 1u);
  const sim::DepthCapture c = physics.capture(0, 0);
  EXPECT_EQ(c.width, 48);
  EXPECT_EQ(c.height, 64);
  EXPECT_EQ(c.returns, 64 * 48);
  const Compared r = compare(c);
  EXPECT_EQ(r.pixels, 64 * 48);
  EXPECT_GT(r.on_cube, 10);      // the cube's top is in view...
  EXPECT_GT(r.on_cube_side, 0);  // ...and its side facing the camera
  EXPECT_LT(r.worst, 1e-6) << "worst range error " << r.worst * 1e3 << " mm";
}

TEST(DepthCamera, TheSameCaptureIsTheSameBitForBit) {
  sim::Physics a(make_scene(R"(, "noise_stddev_m": 0.002, "seed": 7)")), b(make_scene(R"(, "noise_stddev_m": 0.002, "seed": 7)"));
  const auto ca = a.capture(0, 3), cb = b.capture(0, 3), ca2 = a.capture(0, 3);
  ASSERT_EQ(ca.xyz.size(), cb.xyz.size());
  EXPECT_EQ(std::memcmp(ca.xyz.data(), cb.xyz.data(), ca.xyz.size() * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(ca.xyz.data(), ca2.xyz.data(), ca.xyz.size() * sizeof(float)), 0);
  // Another capture index, or another seed: other noise.
  const auto next = a.capture(0, 4);
  EXPECT_NE(std::memcmp(ca.xyz.data(), next.xyz.data(), ca.xyz.size() * sizeof(float)), 0);
  sim::Physics other(make_scene(R"(, "noise_stddev_m": 0.002, "seed": 8)"));
  const auto co = other.capture(0, 3);
  EXPECT_NE(std::memcmp(ca.xyz.data(), co.xyz.data(), ca.xyz.size() * sizeof(float)), 0);
}

TEST(DepthCamera, NoiseHasTheStandardDeviationAskedFor) {
  sim::Physics exact(make_scene()), noisy(make_scene(R"(, "noise_stddev_m": 0.002, "seed": 3)"));
  const auto e = exact.capture(0, 0), n = noisy.capture(0, 0);
  double sum = 0, sum2 = 0;
  int k = 0;
  for (size_t i = 0; i < e.xyz.size(); i += 3) {
    const Eigen::Vector3d pe(e.xyz[i], e.xyz[i + 1], e.xyz[i + 2]), pn(n.xyz[i], n.xyz[i + 1], n.xyz[i + 2]);
    if (std::isnan(pe[0]) || std::isnan(pn[0])) continue;
    const double d = pn.norm() - pe.norm();
    sum += d;
    sum2 += d * d;
    ++k;
  }
  ASSERT_GT(k, 3000);
  const double mean = sum / k, sd = std::sqrt(sum2 / k - mean * mean);
  EXPECT_LT(std::abs(mean), 0.0002);
  EXPECT_NEAR(sd, 0.002, 0.0002);
}

TEST(DepthCamera, CapturingLeavesThePhysicsAsItWas) {
  sim::Physics with(make_scene()), without(make_scene());
  for (int f = 0; f < 20; ++f) {
    if (f % 5 == 0) with.capture(0, f);
    with.step_frame();
    without.step_frame();
  }
  EXPECT_EQ(with.digest(), without.digest());
}

TEST(DepthCamera, AMountedCameraMovesWithItsLinkAndNeverSeesTheLinkItIsIn) {
  sim::Physics physics(make_scene("", R"([{"name": "wrist", "robot": "r", "link": "link6",
      "pose": [0, 0, 0, 0, 0, 0, 1], "width": 16, "height": 12, "near": 0.02}])"));
  const auto c = physics.capture(0, 0);
  EXPECT_EQ(c.camera, "wrist");
  int returns = 0;
  for (size_t i = 0; i < c.xyz.size(); i += 3) {
    if (std::isnan(c.xyz[i])) continue;
    ++returns;  // nothing nearer than near (the range along the ray)
    EXPECT_GE(Eigen::Vector3d(c.xyz[i], c.xyz[i + 1], c.xyz[i + 2]).norm(), 0.02 - 1e-6);
  }
  EXPECT_EQ(returns, c.returns);
  // Its pose is the link's: not the world origin where a fixed camera with this pose would be.
  EXPECT_GT(std::abs(c.pose[2]), 0.1);
}

TEST(DepthCamera, ACameraOnALinkTheRobotDoesNotHaveIsRefusedNamingIt) {
  try {
    sim::Physics physics(make_scene("", R"([{"name": "wrist", "robot": "r", "link": "link9"}])"));
    FAIL() << "built";
  } catch (const scene::SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("cameras[0].link names 'link9'"), std::string::npos) << e.what();
  }
}

TEST(DepthCamera, AskingForACameraTheSceneDoesNotHaveThrows) {
  sim::Physics physics(make_scene());
  EXPECT_THROW(physics.capture(1, 0), std::out_of_range);
}

TEST(DepthCamera, ReturnsOnTheRobotAreMarkedForTheSelfFilter) {
  // Straight down onto the arm's base (at the world origin), and over the table.
  sim::Physics physics(make_scene("", R"([{"name": "down", "pose": [0, 0, 1.5, 1, 0, 0, 0], "width": 8, "height": 6,
      "fov_deg": 4}, {"name": "overhead", "pose": [0.5, 0, 1.2, 1, 0, 0, 0], "width": 48, "height": 64, "fov_deg": 40}])"));
  const auto down = physics.capture(0, 0), table = physics.capture(1, 0);
  ASSERT_EQ(down.on_robot.size(), 48u);
  EXPECT_EQ(std::count(down.on_robot.begin(), down.on_robot.end(), 1), down.returns);
  EXPECT_GT(down.returns, 0);
  EXPECT_EQ(std::count(table.on_robot.begin(), table.on_robot.end(), 1), 0);
}
