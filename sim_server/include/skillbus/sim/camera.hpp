// A simulated depth camera's output and how it travels (docs/perception.md): one capture
// is an organized cloud, a point per pixel in the camera's optical frame, split by rows
// into camera_cloud_t parts that each fit one UDP datagram. No DART here: the ray casting
// is in src/camera.cpp (sim_physics); this is sim_core, unit-tested directly.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "skillbus/scene/scene.hpp"
#include "skillbus_msgs/camera_cloud_t.hpp"

namespace skillbus::sim {

struct DepthCapture {
  std::string camera;
  int width = 0, height = 0;
  std::array<double, 4> intrinsics{};  // fx fy cx cy
  double near = 0, far = 0;            // m along a ray
  scene::Pose pose{};                  // the optical frame in the world at the capture
  // width * height * 3: x y z per pixel, row-major, optical frame (m); NaN: no return.
  std::vector<float> xyz;
  int returns = 0;  // pixels with a return
  // width * height: 1 where the return is on a robot's link (the self filter's mask).
  std::vector<uint8_t> on_robot;
};

// Bytes per part: every part holds as many whole rows of points (12 bytes a pixel) and
// mask (1 bit a pixel) as fit, at least one.
constexpr int kCloudPartBytes = 48 * 1024;
int rows_per_part(int width);  // at least 1

// The capture as the parts published for it, in order. A request's id is echoed;
// `capture` counts the camera's captures.
std::vector<skillbus_msgs::camera_cloud_t> cloud_parts(const DepthCapture& c, const std::string& request_id,
                                                       int64_t capture);
// A refused request's answer: one part with the error and no points.
skillbus_msgs::camera_cloud_t cloud_error(const std::string& camera, const std::string& request_id,
                                          const std::string& error);

// The noise added along a ray: Gaussian, from (seed, capture, pixel) alone, so a capture
// is the same bit for bit on every run whatever order the pixels are cast in.
double ray_noise(uint64_t seed, int64_t capture, int64_t pixel);

}  // namespace skillbus::sim
