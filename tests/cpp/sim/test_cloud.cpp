// A capture as it travels: split by rows into parts of at most kCloudPartBytes, the same
// way every time, the points little-endian float32; a refused request's one error part;
// the noise a pure function of (seed, capture, pixel).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <set>

#include "skillbus/little_endian.hpp"
#include "skillbus/sim/camera.hpp"

using namespace skillbus::sim;

namespace {
DepthCapture capture_of(int w, int h) {
  DepthCapture c;
  c.camera = "overhead";
  c.width = w;
  c.height = h;
  c.intrinsics = {100, 100, (w - 1) / 2.0, (h - 1) / 2.0};
  c.pose = {1, 2, 3, 0, 0, 0, 1};
  c.xyz.resize(static_cast<size_t>(w) * h * 3);
  for (size_t i = 0; i < c.xyz.size(); ++i) c.xyz[i] = static_cast<float>(i) * 0.25f;
  c.xyz[5] = std::nanf("");
  c.on_robot.assign(static_cast<size_t>(w) * h, 0);
  if (c.on_robot.size() > 4100) c.on_robot[4100] = 1;  // (row 25 of a 160-wide image: part 1, its pixel 100)
  return c;
}

float float_at(const std::vector<uint8_t>& b, size_t i) { return skillbus::get_f32_le(&b[i * 4]); }
}  // namespace

TEST(Cloud, PartsCoverEveryRowOnceEachWithinTheDatagramBudget) {
  for (auto [w, h] : std::vector<std::pair<int, int>>{{160, 120}, {640, 480}, {1, 1}, {4096, 3}, {5000, 2}}) {
    const DepthCapture c = capture_of(w, h);
    const auto parts = cloud_parts(c, "req-1", 7);
    int next_row = 0;
    for (size_t p = 0; p < parts.size(); ++p) {
      const auto& m = parts[p];
      EXPECT_EQ(m.part, static_cast<int>(p));
      EXPECT_EQ(m.num_parts, static_cast<int>(parts.size()));
      EXPECT_EQ(m.row_start, next_row);
      EXPECT_EQ(m.request_id, "req-1");
      EXPECT_EQ(m.capture, 7);
      EXPECT_EQ(m.camera, "overhead");
      EXPECT_EQ(m.num_bytes, static_cast<int>(m.points.size()));
      EXPECT_EQ(m.num_bytes, m.num_rows * w * 12);
      EXPECT_EQ(m.num_mask_bytes, (m.num_rows * w + 7) / 8);
      EXPECT_EQ(m.num_mask_bytes, static_cast<int>(m.robot_mask.size()));
      if (m.num_rows > 1) EXPECT_LE(m.num_bytes + m.num_mask_bytes, kCloudPartBytes) << w << "x" << h;  // (one row may be more)
      next_row += m.num_rows;
    }
    EXPECT_EQ(next_row, h) << w << "x" << h;
  }
  EXPECT_EQ(cloud_parts(capture_of(160, 120), "", 0).size(), 5u);  // 25 rows of 160 points (48,000 B) a part
}

TEST(Cloud, PointsAreLittleEndianFloat32InRowMajorOrder) {
  const DepthCapture c = capture_of(160, 120);
  const auto parts = cloud_parts(c, "", 0);
  const auto& second = parts[1];
  const size_t first = static_cast<size_t>(second.row_start) * 160 * 3;
  for (size_t i = 0; i < 30; ++i) EXPECT_EQ(float_at(second.points, i), c.xyz[first + i]);
  EXPECT_TRUE(std::isnan(float_at(parts[0].points, 5)));
  // The robot's pixels: bit 100 of part 1's mask, and no other.
  int set = 0;
  for (const auto& p : parts)
    for (uint8_t b : p.robot_mask) set += __builtin_popcount(b);
  EXPECT_EQ(set, 1);
  EXPECT_EQ(second.robot_mask[100 / 8], 1 << (100 % 8));
  EXPECT_EQ(second.pose[2], 3);
  EXPECT_EQ(second.intrinsics[0], 100);
}

TEST(Cloud, ARefusedRequestIsOnePartWithItsErrorAndNoPoints) {
  const auto m = cloud_error("nope", "r7", "no camera 'nope' in the scene (cameras: overhead)");
  EXPECT_EQ(m.num_parts, 1);
  EXPECT_EQ(m.num_bytes, 0);
  EXPECT_EQ(m.request_id, "r7");
  EXPECT_NE(m.error.find("no camera 'nope'"), std::string::npos);
}

TEST(Cloud, NoiseIsAFunctionOfSeedCaptureAndPixelWithUnitVariance) {
  EXPECT_EQ(ray_noise(1, 2, 3), ray_noise(1, 2, 3));
  std::set<double> distinct{ray_noise(1, 2, 3), ray_noise(2, 2, 3), ray_noise(1, 3, 3), ray_noise(1, 2, 4)};
  EXPECT_EQ(distinct.size(), 4u);
  double sum = 0, sum2 = 0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double x = ray_noise(42, 0, i);
    sum += x;
    sum2 += x * x;
  }
  EXPECT_NEAR(sum / n, 0.0, 0.01);
  EXPECT_NEAR(sum2 / n, 1.0, 0.02);
}
