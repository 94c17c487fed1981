#include "skillbus/sim/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace skillbus::sim {

namespace {

// Peak over mean speed of a minimum-jerk profile (15/8): the move takes long enough that
// its fastest instant stays within the velocity limit.
constexpr double kMinJerkPeak = 1.875;
constexpr int64_t kMinMoveNs = 100'000'000;  // 0.1 s: even a tiny move is smooth

std::string fmt(double v) {
  std::ostringstream o;
  o.precision(4);
  o << v;
  return o.str();
}

}  // namespace

JointTrajectory::JointTrajectory(std::vector<double> start, std::vector<Waypoint> points,
                                 const std::vector<JointLimits>& limits, const std::vector<std::string>& names) {
  const size_t n = start.size();
  if (points.empty()) throw std::invalid_argument("the trajectory has no points");
  for (size_t k = 0; k < points.size(); ++k) {
    const Waypoint& p = points[k];
    if (p.q.size() != n)
      throw std::invalid_argument("point " + std::to_string(k) + " has " + std::to_string(p.q.size()) +
                                  " positions for " + std::to_string(n) + " joints");
    if (!p.qd.empty() && p.qd.size() != n)
      throw std::invalid_argument("point " + std::to_string(k) + " has " + std::to_string(p.qd.size()) +
                                  " velocities for " + std::to_string(n) + " joints");
    if (p.t_ns < 0) throw std::invalid_argument("point " + std::to_string(k) + " has a negative time");
    if (k > 0 && p.t_ns <= points[k - 1].t_ns)
      throw std::invalid_argument("point " + std::to_string(k) + " is not later than point " + std::to_string(k - 1));
    for (size_t j = 0; j < n; ++j) {
      if (!std::isfinite(p.q[j]) || (!p.qd.empty() && !std::isfinite(p.qd[j])))
        throw std::invalid_argument("point " + std::to_string(k) + " of " + names[j] + " is not a finite number");
      if (p.q[j] < limits[j].lower - 1e-9 || p.q[j] > limits[j].upper + 1e-9)
        throw std::invalid_argument(names[j] + " target " + fmt(p.q[j]) + " at point " + std::to_string(k) +
                                    " is outside its limits [" + fmt(limits[j].lower) + ", " + fmt(limits[j].upper) + "]");
      if (!p.qd.empty() && std::abs(p.qd[j]) > limits[j].velocity + 1e-9)
        throw std::invalid_argument(names[j] + " velocity " + fmt(p.qd[j]) + " at point " + std::to_string(k) +
                                    " exceeds its limit " + fmt(limits[j].velocity));
    }
  }

  Waypoint first;
  first.t_ns = 0;
  first.q = std::move(start);
  first.qd.assign(n, 0.0);

  if (points.size() == 1 && points[0].t_ns == 0) {
    // A position target: time the move by the slowest joint.
    double seconds = 0;
    for (size_t j = 0; j < n; ++j)
      seconds = std::max(seconds, kMinJerkPeak * std::abs(points[0].q[j] - first.q[j]) / limits[j].velocity);
    Waypoint last = points[0];
    last.t_ns = std::max<int64_t>(kMinMoveNs, static_cast<int64_t>(std::ceil(seconds * 1e3)) * 1'000'000);
    last.qd.assign(n, 0.0);
    points_ = {first, last};
    min_jerk_ = true;
    return;
  }
  if (points[0].t_ns == 0) throw std::invalid_argument("a trajectory of several points must start after t = 0");

  points_.push_back(first);
  for (auto& p : points) points_.push_back(std::move(p));
  // Mean speed of each segment within the limit; missing velocities from neighbours.
  for (size_t k = 1; k < points_.size(); ++k) {
    const double dt = (points_[k].t_ns - points_[k - 1].t_ns) * 1e-9;
    for (size_t j = 0; j < n; ++j) {
      const double v = std::abs(points_[k].q[j] - points_[k - 1].q[j]) / dt;
      if (v > limits[j].velocity + 1e-9)
        throw std::invalid_argument(names[j] + " would move at " + fmt(v) + " rad/s to point " + std::to_string(k - 1) +
                                    "; its limit is " + fmt(limits[j].velocity));
    }
  }
  for (size_t k = 1; k < points_.size(); ++k) {
    if (!points_[k].qd.empty()) continue;
    points_[k].qd.assign(n, 0.0);
    if (k + 1 == points_.size()) continue;  // the last point is a stop
    const double dt0 = (points_[k].t_ns - points_[k - 1].t_ns) * 1e-9;
    const double dt1 = (points_[k + 1].t_ns - points_[k].t_ns) * 1e-9;
    for (size_t j = 0; j < n; ++j) {
      const double v0 = (points_[k].q[j] - points_[k - 1].q[j]) / dt0;
      const double v1 = (points_[k + 1].q[j] - points_[k].q[j]) / dt1;
      // Zero at a turning point, so the path never overshoots a waypoint.
      points_[k].qd[j] = (v0 * v1 <= 0) ? 0.0 : 0.5 * (v0 + v1);
    }
  }
}

Sample JointTrajectory::sample(int64_t t_ns) const {
  Sample s;
  const size_t n = points_.front().q.size();
  s.q.resize(n);
  s.qd.assign(n, 0.0);
  s.qdd.assign(n, 0.0);
  if (t_ns >= points_.back().t_ns) {
    s.q = points_.back().q;
    return s;
  }
  if (t_ns <= 0) {
    s.q = points_.front().q;
    return s;
  }
  size_t k = 1;
  while (points_[k].t_ns < t_ns) ++k;
  const Waypoint& a = points_[k - 1];
  const Waypoint& b = points_[k];
  const double T = (b.t_ns - a.t_ns) * 1e-9;
  const double u = (t_ns - a.t_ns) * 1e-9 / T;
  if (min_jerk_) {
    const double u3 = u * u * u;
    const double p = u3 * (10 - 15 * u + 6 * u * u);
    const double dp = 30 * u * u * (1 - u) * (1 - u) / T;
    const double ddp = 60 * u * (1 - u) * (1 - 2 * u) / (T * T);
    for (size_t j = 0; j < n; ++j) {
      const double d = b.q[j] - a.q[j];
      s.q[j] = a.q[j] + d * p;
      s.qd[j] = d * dp;
      s.qdd[j] = d * ddp;
    }
    return s;
  }
  // Cubic Hermite on [0, 1] scaled by T.
  const double u2 = u * u, u3 = u2 * u;
  const double h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
  const double d00 = 6 * u2 - 6 * u, d10 = 3 * u2 - 4 * u + 1, d01 = -6 * u2 + 6 * u, d11 = 3 * u2 - 2 * u;
  const double e00 = 12 * u - 6, e10 = 6 * u - 4, e01 = -12 * u + 6, e11 = 6 * u - 2;
  for (size_t j = 0; j < n; ++j) {
    const double m0 = a.qd[j] * T, m1 = b.qd[j] * T;
    s.q[j] = h00 * a.q[j] + h10 * m0 + h01 * b.q[j] + h11 * m1;
    s.qd[j] = (d00 * a.q[j] + d10 * m0 + d01 * b.q[j] + d11 * m1) / T;
    s.qdd[j] = (e00 * a.q[j] + e10 * m0 + e01 * b.q[j] + e11 * m1) / (T * T);
  }
  return s;
}

}  // namespace skillbus::sim
