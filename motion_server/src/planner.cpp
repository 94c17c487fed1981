#include "skillbus/motion/planner.hpp"

#include <algorithm>
#include <cmath>

namespace skillbus::motion {

namespace {

constexpr double kPeakOverMean = 1.5;      // a cubic segment with resting ends peaks at 1.5x its mean speed
constexpr double kCartesianSpeed = 0.1;    // m/s of the tool along a line (at speed_scale 1)
constexpr int64_t kMinSegmentNs = 50'000'000;
constexpr double kMaxJointJump = 0.5;      // rad between neighbouring line waypoints: a branch switch
// An IK solve per waypoint costs up to milliseconds: a line of more waypoints than this (a
// step_m of 1e-7: millions) kept the service busy for minutes and deaf to every other
// request. 2 m in 1 mm steps.
constexpr double kMaxWaypoints = 2000;

int64_t segment_ns(const Kinematics& k, const Eigen::VectorXd& a, const Eigen::VectorXd& b, double scale,
                   double min_s) {
  double t = min_s;
  for (size_t i = 0; i < k.joints().size(); ++i) {
    const auto j = static_cast<Eigen::Index>(i);
    t = std::max(t, kPeakOverMean * std::abs(b[j] - a[j]) / (scale * k.joints()[i].velocity));
  }
  const auto ns = static_cast<int64_t>(std::ceil(t * 100.0)) * 10'000'000;  // whole 10 ms
  return std::max(ns, kMinSegmentNs);
}

}  // namespace

Plan plan_motion(const Kinematics& k, const PlanRequest& req) {
  Plan plan;
  const double scale = req.speed_scale > 0 ? std::min(req.speed_scale, 1.0) : 0.5;
  const double step = req.step_m > 0 ? req.step_m : 0.01;
  const Eigen::Isometry3d from = k.tool_pose(req.start);
  if (!req.cartesian) {
    const IkResult ik = solve_ik(k, req.target, req.start);
    plan.seeds_tried = ik.seeds_tried;
    plan.position_error = ik.position_error;
    plan.orientation_error = ik.orientation_error;
    if (!ik.ok) {
      plan.error = ik.error;
      return plan;
    }
    plan.goal = ik.q;
    plan.points.emplace_back(segment_ns(k, req.start, ik.q, scale, 0.0), ik.q);
    plan.ok = true;
    return plan;
  }
  const double dist = (req.target.translation() - from.translation()).norm();
  const double waypoints = std::ceil(dist / step);
  if (!(waypoints <= kMaxWaypoints)) {  // (also NaN)
    plan.error = "along the line: " + std::to_string(dist) + " m every " + std::to_string(step) + " m is more than " +
                 std::to_string(static_cast<int>(kMaxWaypoints)) + " waypoints; give a larger step_m";
    return plan;
  }
  const int n = std::max(1, static_cast<int>(waypoints));
  const Eigen::Quaterniond qa(from.linear()), qb(req.target.linear());
  Eigen::VectorXd prev = req.start;
  int64_t t = 0;
  for (int i = 1; i <= n; ++i) {
    const double u = static_cast<double>(i) / n;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = (1 - u) * from.translation() + u * req.target.translation();
    pose.linear() = qa.slerp(u, qb).toRotationMatrix();
    const IkResult ik = solve_ik(k, pose, prev);
    plan.seeds_tried += ik.seeds_tried;
    if (!ik.ok) {
      plan.error = "along the line, waypoint " + std::to_string(i) + " of " + std::to_string(n) + ": " + ik.error;
      return plan;
    }
    if ((ik.q - prev).cwiseAbs().maxCoeff() > kMaxJointJump) {
      plan.error = "along the line, waypoint " + std::to_string(i) + " of " + std::to_string(n) +
                   ": the arm would have to change its configuration (a joint jumps by more than 0.5 rad)";
      return plan;
    }
    t += segment_ns(k, prev, ik.q, scale, (dist / n) / (kCartesianSpeed * scale * 2));
    plan.points.emplace_back(t, ik.q);
    prev = ik.q;
    plan.position_error = ik.position_error;
    plan.orientation_error = ik.orientation_error;
  }
  plan.goal = prev;
  plan.ok = true;
  return plan;
}

}  // namespace skillbus::motion
