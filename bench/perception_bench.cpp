// Benchmark: the depth camera and the occupancy map (docs/benchmarks.md, "Perception").
//
// 1. Capture time per image size: the demo scene's overhead camera at 80x60 .. 640x480
//    (the same field of view), the median of 5 captures, and per ray.
// 2. Map insertion: the demo's 320x240 capture into an empty 1 cm map as map_server takes
//    it (its parts assembled, the rays thinned to about one per voxel where the camera
//    looks, end points discretized), beside OctoMap's own default insertion of every
//    point (insertPointCloud, a ray per point) in the same run; the capture's points per
//    second and the ratio.
//
// Run: build/bench/perception_bench [SCENE]   (in `make bench`)
#include <octomap/OcTree.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "cloud_input.hpp"  // (map_server's private header: a benchmark of its own path)
#include "skillbus/map/occupancy_map.hpp"
#include "skillbus/scene/scene.hpp"
#include "skillbus/sim/physics.hpp"

using namespace skillbus;
using clk = std::chrono::steady_clock;

namespace {
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

template <class F>
double time_s(F&& f) {
  const auto t0 = clk::now();
  f();
  return std::chrono::duration<double>(clk::now() - t0).count();
}
}  // namespace

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? argv[1] : std::string(SKILLBUS_SOURCE_DIR) + "/deploy/scenes/demo.scene.json";
  const scene::Scene base = scene::load_scene(path);
  if (base.cameras.empty()) {
    std::fprintf(stderr, "%s has no camera\n", path.c_str());
    return 2;
  }
  std::printf("perception benchmark, scene %s, camera %s\n", path.c_str(), base.cameras[0].name.c_str());
  std::printf("%12s %8s %12s %10s %9s\n", "image", "rays", "capture ms", "us/ray", "returns");
  sim::DepthCapture demo_capture;
  for (auto [w, h] : std::vector<std::pair<int, int>>{{80, 60}, {160, 120}, {320, 240}, {640, 480}}) {
    scene::Scene s = base;
    auto& c = s.cameras[0];
    const double scale = static_cast<double>(h) / c.height;
    c.fx *= scale, c.fy *= scale, c.cx = (w - 1) / 2.0, c.cy = (h - 1) / 2.0;
    c.width = w, c.height = h;
    c.noise_stddev_m = 0;
    sim::Physics physics(s);
    std::vector<double> t;
    sim::DepthCapture cap;
    for (int i = 0; i < 5; ++i) t.push_back(time_s([&] { cap = physics.capture(0, i); }));
    const double ms = 1e3 * median(t);
    std::printf("%5dx%-6d %8d %12.2f %10.3f %9d\n", w, h, w * h, ms, 1e3 * ms / (w * h), cap.returns);
    if (w == 320) demo_capture = cap;
  }

  // The 320x240 capture in the world frame.
  const auto& p = demo_capture.pose;
  const Eigen::Isometry3d T = Eigen::Translation3d(p[0], p[1], p[2]) * Eigen::Quaterniond(p[6], p[3], p[4], p[5]);
  std::vector<map::Vec3> hits;
  octomap::Pointcloud cloud;
  for (size_t i = 0; i < demo_capture.xyz.size(); i += 3) {
    if (std::isnan(demo_capture.xyz[i]) || demo_capture.on_robot[i / 3]) continue;
    const Eigen::Vector3d w = T * Eigen::Vector3d(demo_capture.xyz[i], demo_capture.xyz[i + 1], demo_capture.xyz[i + 2]);
    hits.push_back({w.x(), w.y(), w.z()});
    cloud.push_back(static_cast<float>(w.x()), static_cast<float>(w.y()), static_cast<float>(w.z()));
  }
  const auto parts = sim::cloud_parts(demo_capture, "", 0);
  std::vector<double> ours, peer;
  int stride = 1;
  for (int i = 0; i < 3; ++i) {
    map::OccupancyMap m(0.01);
    ours.push_back(time_s([&] {
      map::CloudParts assembler;
      for (const auto& part : parts)
        if (auto c = assembler.add(part, m.resolution())) {
          m.insert(c->hits, c->misses, c->origin, c->far);
          stride = c->stride;
        }
    }));
    octomap::OcTree t(0.01);
    peer.push_back(time_s([&] { t.insertPointCloud(cloud, octomap::point3d(p[0], p[1], p[2]), demo_capture.far); }));
  }
  const double ours_pps = hits.size() / median(ours), peer_pps = hits.size() / median(peer);
  std::printf("\nmap insertion, 1 cm voxels, %zu points of the 320x240 capture (median of 3):\n", hits.size());
  std::printf("  map_server (a ray every %d pixels, discretized) %8.1f ms  %10.0f points/s\n", stride, 1e3 * median(ours),
              ours_pps);
  std::printf("  OctoMap's insertPointCloud (a ray a point)     %8.1f ms  %10.0f points/s\n", 1e3 * median(peer), peer_pps);
  std::printf("  ratio (map_server / OctoMap's default)         %8.2fx\n", ours_pps / peer_pps);
  return 0;
}
