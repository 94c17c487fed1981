// Private to map_server: a depth camera's capture put back together from its
// camera_cloud_t parts (lcmtypes/camera_cloud_t.lcm) as the map takes it: the sensor's
// origin, the returns and the rays without one, in the world frame, thinned to about one
// ray per voxel on the nearer surfaces.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "skillbus/map/occupancy_map.hpp"
#include "skillbus_msgs/camera_cloud_t.hpp"

namespace skillbus::map {

struct WorldCloud {
  std::string camera;
  int64_t capture = 0;
  Vec3 origin{};
  std::vector<Vec3> hits;    // surfaces seen
  std::vector<Vec3> misses;  // beyond `far` along the rays that saw nothing
  double far = 0;
  int stride = 1;  // every stride-th pixel of every stride-th row was taken
};

// The pixel stride that spaces the rays about one voxel apart at `depth` (map_server
// takes the first quartile of a cloud's depths): denser rays end in the same voxels and
// cost a ray cast each.
int ray_stride(double voxel, double fx, double depth);

class CloudParts {
 public:
  // The capture this part completes (std::nullopt before). A part that cannot be
  // (sizes that do not add up, parts of one capture that disagree) throws
  // std::invalid_argument saying why; an error part (a refused request) is ignored.
  std::optional<WorldCloud> add(const skillbus_msgs::camera_cloud_t& part, double voxel = 0);
  static constexpr size_t kKeep = 8;  // incomplete captures held (the oldest goes first)

 private:
  std::map<std::pair<std::string, int64_t>, std::map<int32_t, skillbus_msgs::camera_cloud_t>> open_;
  std::vector<std::pair<std::string, int64_t>> order_;  // of open_, oldest first
};

}  // namespace skillbus::map
