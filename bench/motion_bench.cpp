// Planning time of the demo's motions (issue "Perception", motion that avoids obstacles):
// each cube of the demo scene picked and carried to the bin, past the post, as the skills
// ask the motion service: to over the cube (joint space), down and up (lines, the second
// holding the cube), to over the bin (joint space, holding it: the move that goes around
// the post), down into the bin and up (lines). Each motion planned `repeats` times with
// the collision model (the post, the fixtures, the held cube) and, in the same run, without
// it (the planner as it was before: IK and timing only). Median and 95th percentile.
//
// Run: build/bench/motion_bench [repeats]   (in `make bench`)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "skillbus/motion/collision.hpp"
#include "skillbus/motion/planner.hpp"

using namespace skillbus;
using namespace skillbus::motion;

namespace {

Eigen::Isometry3d top_down(double x, double y, double z) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, y, z);
  T.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix();
  return T;
}

struct Motion {
  std::string kind;  // what the skills do: "to a cube", "line", "to the bin"
  PlanRequest req;
};

double percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  const size_t i = std::min(v.size() - 1, static_cast<size_t>(std::ceil(p * v.size())) - 1);
  return v[i];
}

}  // namespace

int main(int argc, char** argv) {
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 20;
  const scene::Scene scene = scene::load_scene(std::string(SKILLBUS_SOURCE_DIR) + "/deploy/scenes/demo.scene.json");
  Kinematics k(scene);
  CollisionModel world(scene);
  const Eigen::Vector3d cube = Eigen::Vector3d::Constant(0.05), none = Eigen::Vector3d::Zero();

  // The demo's sequence, each motion starting where the last one ended.
  std::vector<Motion> motions;
  Eigen::VectorXd q(6);
  q << 0.0, 0.2, 1.6, 0.0, 1.3416, 0.0;  // the scene's initial joints
  auto add = [&](const std::string& kind, const Eigen::Isometry3d& target, bool line, const Eigen::Vector3d& held) {
    Motion m{kind, {}};
    m.req.start = q;
    m.req.target = target;
    m.req.cartesian = line;
    m.req.held = held;
    const Plan p = plan_motion(k, m.req, &world);
    if (!p.ok) {
      std::fprintf(stderr, "motion_bench: %s: %s\n", kind.c_str(), p.error.c_str());
      std::exit(1);
    }
    q = p.goal;
    motions.push_back(m);
  };
  for (const auto& o : scene.objects) {
    const double x = o.pose[0], y = o.pose[1], z = o.pose[2];
    add("to over a cube", top_down(x, y, z + 0.10), false, none);
    add("line", top_down(x, y, z + 0.005), true, none);
    add("line", top_down(x, y, z + 0.105), true, cube);
    add("to over the bin", top_down(0.0, 0.6, 0.45), false, cube);
    add("line", top_down(0.0, 0.6, 0.30), true, cube);
    add("line", top_down(0.0, 0.6, 0.40), true, none);
  }

  std::printf("motion planning, the demo's %zu motions (3 cubes), %d repeats each, in ms:\n", motions.size(), repeats);
  std::printf("  %-16s %8s %8s %8s %8s %8s  %s\n", "motion", "n", "median", "p95", "before", "ratio", "how (iterations)");
  std::map<std::string, std::vector<double>> with, without;
  std::map<std::string, std::string> how;
  using clock = std::chrono::steady_clock;
  for (int r = 0; r < repeats; ++r)
    for (const Motion& m : motions) {
      auto t0 = clock::now();
      const Plan p = plan_motion(k, m.req, &world);
      auto t1 = clock::now();
      plan_motion(k, m.req, nullptr);
      auto t2 = clock::now();
      with[m.kind].push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
      without[m.kind].push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
      if (r == 0 && m.kind == "to over the bin")
        how[m.kind] += (how[m.kind].empty() ? "" : ", ") + p.how + " (" + std::to_string(p.iterations) + ")";
      else if (r == 0 && how[m.kind].empty())
        how[m.kind] = p.how;
    }
  std::vector<double> all_with, all_without;
  for (const auto& [kind, v] : with) {
    const double med = percentile(v, 0.5), before = percentile(without[kind], 0.5);
    std::printf("  %-16s %8zu %8.2f %8.2f %8.2f %7.2fx  %s\n", kind.c_str(), v.size(), med, percentile(v, 0.95), before,
                med / before, how[kind].c_str());
    all_with.insert(all_with.end(), v.begin(), v.end());
    all_without.insert(all_without.end(), without[kind].begin(), without[kind].end());
  }
  std::printf("  %-16s %8zu %8.2f %8.2f %8.2f %7.2fx\n", "all", all_with.size(), percentile(all_with, 0.5),
              percentile(all_with, 0.95), percentile(all_without, 0.5),
              percentile(all_with, 0.5) / percentile(all_without, 0.5));
  std::printf("  (median and p95 with the collision model; 'before': the median without it, IK and timing only)\n");
  return 0;
}
