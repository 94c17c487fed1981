#include "cloud_input.hpp"

#include "skillbus/little_endian.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace skillbus::map {

namespace {

void check(const skillbus_msgs::camera_cloud_t& m) {
  auto bad = [&](const std::string& why) {
    throw std::invalid_argument("part " + std::to_string(m.part) + " of capture " + std::to_string(m.capture) +
                                " of camera '" + m.camera + "': " + why);
  };
  if (m.width <= 0 || m.height <= 0 || int64_t{m.width} * m.height > (1 << 20)) bad("no image size");
  if (m.part < 0 || m.part >= m.num_parts || m.num_parts > m.height) bad("part number out of range");
  if (m.row_start < 0 || m.num_rows <= 0 || int64_t{m.row_start} + m.num_rows > m.height) bad("rows out of the image");
  if (int64_t{m.num_bytes} != int64_t{m.num_rows} * m.width * 12 || m.points.size() != static_cast<size_t>(m.num_bytes))
    bad("the points' bytes do not match its rows");
  if (int64_t{m.num_mask_bytes} != (int64_t{m.num_rows} * m.width + 7) / 8 ||
      m.robot_mask.size() != static_cast<size_t>(m.num_mask_bytes))
    bad("the robot mask's bytes do not match its rows");
  for (double v : m.pose)
    if (!std::isfinite(v)) bad("pose not finite");
  if (!(m.range[0] > 0 && m.range[0] < m.range[1] && std::isfinite(m.range[1]))) bad("range not 0 < near < far");
}

float float_at(const std::vector<uint8_t>& b, size_t i) { return get_f32_le(&b[i * 4]); }

}  // namespace

int ray_stride(double voxel, double fx, double depth) {
  if (!(voxel > 0) || !(fx > 0) || !(depth > 0)) return 1;
  return std::max(1, static_cast<int>(std::lround(voxel * fx / depth)));
}

std::optional<WorldCloud> CloudParts::add(const skillbus_msgs::camera_cloud_t& m, double voxel) {
  if (!m.error.empty()) return std::nullopt;
  check(m);
  const auto key = std::make_pair(m.camera, m.capture);
  auto& parts = open_[key];
  if (parts.empty()) order_.push_back(key);
  if (!parts.empty()) {
    const auto& first = parts.begin()->second;
    bool same = first.width == m.width && first.height == m.height && first.num_parts == m.num_parts;
    for (int i = 0; i < 7; ++i) same = same && first.pose[i] == m.pose[i];
    if (!same) {
      open_.erase(key);
      order_.erase(std::find(order_.begin(), order_.end(), key));
      throw std::invalid_argument("part " + std::to_string(m.part) + " of capture " + std::to_string(m.capture) +
                                  " of camera '" + m.camera + "' does not match its other parts");
    }
  }
  parts[m.part] = m;
  while (order_.size() > kKeep) {
    open_.erase(order_.front());
    order_.erase(order_.begin());
  }
  if (open_.count(key) == 0 || parts.size() < static_cast<size_t>(m.num_parts)) return std::nullopt;
  const auto whole = std::move(parts);
  open_.erase(key);
  order_.erase(std::find(order_.begin(), order_.end(), key));

  WorldCloud out;
  out.camera = m.camera;
  out.capture = m.capture;
  out.far = m.range[1];
  const Eigen::Vector3d t(m.pose[0], m.pose[1], m.pose[2]);
  const Eigen::Matrix3d R = Eigen::Quaterniond(m.pose[6], m.pose[3], m.pose[4], m.pose[5]).normalized().toRotationMatrix();
  out.origin = {t.x(), t.y(), t.z()};
  const double fx = m.intrinsics[0], fy = m.intrinsics[1], cx = m.intrinsics[2], cy = m.intrinsics[3];
  if (!(fx > 0 && fy > 0)) throw std::invalid_argument("capture of camera '" + m.camera + "': focal length <= 0");
  // The depth of the nearer returns (the first quartile), for the stride: where the rays
  // are densest per voxel (the floor beyond a table is seen more thinly).
  std::vector<float> depths;
  for (const auto& [i, p] : whole)
    for (size_t k = 2; k < p.points.size() / 4; k += 3)
      if (!std::isnan(float_at(p.points, k))) depths.push_back(float_at(p.points, k));
  if (!depths.empty()) {
    std::nth_element(depths.begin(), depths.begin() + depths.size() / 4, depths.end());
    out.stride = ray_stride(voxel, fx, depths[depths.size() / 4]);
  }
  int32_t row = 0;
  for (const auto& [i, p] : whole) {
    if (p.row_start != row)
      throw std::invalid_argument("capture " + std::to_string(m.capture) + " of camera '" + m.camera + "': part " +
                                  std::to_string(i) + " starts at row " + std::to_string(p.row_start) + ", not " +
                                  std::to_string(row));
    for (int32_t r = 0; r < p.num_rows; ++r)
      for (int32_t u = 0; u < p.width; ++u) {
        if ((p.row_start + r) % out.stride != 0 || u % out.stride != 0) continue;
        const size_t px = static_cast<size_t>(r) * p.width + u, k = px * 3;
        // The robot's own returns (the self filter) are left out: the map is the world's.
        if (p.robot_mask[px / 8] & (1u << (px % 8))) continue;
        const Eigen::Vector3d q(float_at(p.points, k), float_at(p.points, k + 1), float_at(p.points, k + 2));
        if (std::isnan(q.z())) {  // nothing seen along this pixel's ray up to far
          const int32_t v = p.row_start + r;
          const Eigen::Vector3d dir = Eigen::Vector3d((u - cx) / fx, (v - cy) / fy, 1.0).normalized();
          const Eigen::Vector3d w = t + R * (dir * (1.5 * out.far));
          out.misses.push_back({w.x(), w.y(), w.z()});
          continue;
        }
        const Eigen::Vector3d w = t + R * q;
        out.hits.push_back({w.x(), w.y(), w.z()});
      }
    row += p.num_rows;
  }
  if (row != m.height)
    throw std::invalid_argument("capture " + std::to_string(m.capture) + " of camera '" + m.camera + "': its parts hold " +
                                std::to_string(row) + " of " + std::to_string(m.height) + " rows");
  return out;
}

}  // namespace skillbus::map
