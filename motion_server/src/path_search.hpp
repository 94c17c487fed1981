// Private to motion_core: a joint-space path around obstacles with OMPL (RRTConnect),
// reproducible: the sampler is seeded per search and the search is bounded by a number of
// iterations, not by time. OMPL stays in path_search.cpp.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace skillbus::motion {

struct PathSearchOptions {
  uint32_t seed = 1;
  int max_iterations = 20000;  // RRTConnect's sample-and-extend steps
  double range = 0.4;          // rad: the longest edge the trees grow by
};

struct PathSearch {
  bool ok = false;
  std::vector<Eigen::VectorXd> path;  // start ... goal
  int iterations = 0;
};

// valid(q): the arm may be at q; segment_clear(a, b): every state on the straight joint
// segment a-b is valid (OMPL checks motions with it, as the shortcut does).
PathSearch search_path(const Eigen::VectorXd& start, const Eigen::VectorXd& goal, const Eigen::VectorXd& lower,
                       const Eigen::VectorXd& upper, const std::function<bool(const Eigen::VectorXd&)>& valid,
                       const std::function<bool(const Eigen::VectorXd&, const Eigen::VectorXd&)>& segment_clear,
                       const PathSearchOptions& options);

// The path with as many waypoints left out as straight segments allow: from each kept
// waypoint, on to the farthest later one it sees (deterministic).
std::vector<Eigen::VectorXd> shortcut(const std::vector<Eigen::VectorXd>& path,
                                      const std::function<bool(const Eigen::VectorXd&, const Eigen::VectorXd&)>& segment_clear);

}  // namespace skillbus::motion
