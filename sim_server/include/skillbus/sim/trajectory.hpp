// Joint trajectories for the arm controller: a timed list of waypoints played with
// cubic Hermite segments, or a single position target played as a minimum-jerk move
// whose duration follows from the joints' velocity limits. Pure arithmetic on
// std::vector, no DART: the controller samples it once per physics step.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace skillbus::sim {

struct Waypoint {
  int64_t t_ns = 0;                 // from the trajectory's start
  std::vector<double> q;            // one per joint
  std::vector<double> qd;           // empty: derived
};

struct JointLimits {
  double lower = -1e9, upper = 1e9, velocity = 1e9;
};

struct Sample {
  std::vector<double> q, qd, qdd;
};

class JointTrajectory {
 public:
  JointTrajectory() = default;
  // A trajectory from `start` (the current targets) through `points`. Throws
  // std::invalid_argument naming the problem (time order, limits, speed). A single point
  // at t = 0 becomes a minimum-jerk move timed by the velocity limits.
  JointTrajectory(std::vector<double> start, std::vector<Waypoint> points, const std::vector<JointLimits>& limits,
                  const std::vector<std::string>& names);

  Sample sample(int64_t t_ns) const;
  int64_t duration_ns() const { return points_.empty() ? 0 : points_.back().t_ns; }
  bool empty() const { return points_.empty(); }
  const std::vector<double>& final_positions() const { return points_.back().q; }

 private:
  std::vector<Waypoint> points_;    // points_[0] is the start at t = 0
  bool min_jerk_ = false;
};

}  // namespace skillbus::sim
