#include <algorithm>
#include <cmath>
#include <cstring>

#include "skillbus/little_endian.hpp"
#include "skillbus/sim/camera.hpp"

namespace skillbus::sim {

namespace {

constexpr int kPointBytes = 12;  // x y z, float32

uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

double unit_open(uint64_t bits) { return (static_cast<double>(bits >> 11) + 0.5) * (1.0 / 9007199254740992.0); }

}  // namespace

int rows_per_part(int width) {
  if (width <= 0) return 1;
  // 12 bytes of points and 1/8 byte of mask a pixel: rows * width * 97 / 8 <= the budget.
  return std::max(1, static_cast<int>((int64_t{kCloudPartBytes} * 8) / (int64_t{width} * (kPointBytes * 8 + 1))));
}

std::vector<skillbus_msgs::camera_cloud_t> cloud_parts(const DepthCapture& c, const std::string& request_id,
                                                       int64_t capture) {
  const int rows = rows_per_part(c.width);
  const int parts = std::max(1, (c.height + rows - 1) / rows);
  std::vector<skillbus_msgs::camera_cloud_t> out;
  out.reserve(parts);
  for (int p = 0; p < parts; ++p) {
    skillbus_msgs::camera_cloud_t m{};
    m.camera = c.camera;
    m.request_id = request_id;
    m.capture = capture;
    m.width = c.width;
    m.height = c.height;
    for (int i = 0; i < 4; ++i) m.intrinsics[i] = c.intrinsics[i];
    m.range[0] = c.near;
    m.range[1] = c.far;
    for (int i = 0; i < 7; ++i) m.pose[i] = c.pose[i];
    m.part = p;
    m.num_parts = parts;
    m.row_start = p * rows;
    m.num_rows = std::min(rows, c.height - m.row_start);
    const size_t first = static_cast<size_t>(m.row_start) * c.width * 3;
    const size_t count = static_cast<size_t>(m.num_rows) * c.width * 3;
    m.points.resize(count * 4);
    for (size_t i = 0; i < count; ++i) put_f32_le(c.xyz[first + i], &m.points[i * 4]);
    m.num_bytes = static_cast<int32_t>(m.points.size());
    const size_t pixels = static_cast<size_t>(m.num_rows) * c.width, first_pixel = first / 3;
    m.robot_mask.assign((pixels + 7) / 8, 0);
    if (!c.on_robot.empty())
      for (size_t i = 0; i < pixels; ++i)
        if (c.on_robot[first_pixel + i]) m.robot_mask[i / 8] |= static_cast<uint8_t>(1u << (i % 8));
    m.num_mask_bytes = static_cast<int32_t>(m.robot_mask.size());
    out.push_back(std::move(m));
  }
  return out;
}

skillbus_msgs::camera_cloud_t cloud_error(const std::string& camera, const std::string& request_id,
                                          const std::string& error) {
  skillbus_msgs::camera_cloud_t m{};
  m.camera = camera;
  m.request_id = request_id;
  m.capture = -1;
  m.error = error;
  m.num_parts = 1;
  return m;
}

double ray_noise(uint64_t seed, int64_t capture, int64_t pixel) {
  const uint64_t k = splitmix64(splitmix64(seed) ^ splitmix64(static_cast<uint64_t>(capture) * 0x100000001b3ULL) ^
                                static_cast<uint64_t>(pixel));
  // Box-Muller with two uniforms from one key (std::normal_distribution's algorithm is
  // the library's choice: not the same everywhere).
  const double u1 = unit_open(k), u2 = unit_open(splitmix64(k));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

}  // namespace skillbus::sim
