#include "skillbus/motion/planner.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "path_search.hpp"
#include "segment_order.hpp"

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

std::string describe(const std::vector<Touch>& touches) {
  std::string out;
  for (const auto& t : touches) {
    if (!out.empty()) out += ", ";
    out += t.part + " into '" + t.body + "'" + (t.obstacle ? " (an obstacle)" : "");
  }
  return out;
}

std::vector<Touch> new_touches(const CollisionModel& world, const Eigen::VectorXd& q, const std::vector<Touch>& allowed) {
  std::vector<Touch> out;
  for (const auto& t : world.touches(q))
    if (std::find(allowed.begin(), allowed.end(), t) == allowed.end()) out.push_back(t);
  return out;
}

// What the arm checks against on its way: the collision model, less the contacts it
// starts in (a cube just grasped still rests on the table).
struct Checker {
  const CollisionModel& world;
  std::vector<Touch> allowed;
  double step;
  bool valid(const Eigen::VectorXd& q) const { return world.clear(q, allowed); }
  bool segment_clear(const Eigen::VectorXd& a, const Eigen::VectorXd& b) const {
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).cwiseAbs().maxCoeff() / step)));
    return all_valid_coarse_to_fine(n, [&](int i) { return valid(a + (b - a) * (static_cast<double>(i) / n)); });
  }
};

// The straight joint segment to the goal touches something: a path around it, its
// waypoints as few as straight segments allow, the arm resting at each.
Plan plan_around(const Kinematics& k, const PlanRequest& req, const Checker& check, Plan plan, double scale,
                 const PlannerOptions& options) {
  const auto n = static_cast<Eigen::Index>(k.joints().size());
  Eigen::VectorXd lower(n), upper(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    lower[i] = k.joints()[static_cast<size_t>(i)].lower;
    upper[i] = k.joints()[static_cast<size_t>(i)].upper;
  }
  auto valid = [&](const Eigen::VectorXd& q) { return check.valid(q); };
  auto clear = [&](const Eigen::VectorXd& a, const Eigen::VectorXd& b) { return check.segment_clear(a, b); };
  PathSearchOptions search;
  search.seed = options.seed;
  search.max_iterations = options.max_iterations;
  const PathSearch found = search_path(req.start, plan.goal, lower, upper, valid, clear, search);
  plan.how = "around";
  plan.iterations = found.iterations;
  if (!found.ok) {
    // Name what is in the way: the first state of the straight segment that touches.
    std::string what;
    const int steps = 100;
    for (int i = 1; i <= steps && what.empty(); ++i) {
      const Eigen::VectorXd q = req.start + (plan.goal - req.start) * (static_cast<double>(i) / steps);
      what = describe(new_touches(check.world, q, check.allowed));
    }
    plan.error = "no path around " + (what.empty() ? std::string("what is in the way") : what) + " within " +
                 std::to_string(options.max_iterations) + " iterations of the path search";
    return plan;
  }
  const std::vector<Eigen::VectorXd> path = shortcut(found.path, clear);
  int64_t t = 0;
  for (size_t i = 1; i < path.size(); ++i) {
    t += segment_ns(k, path[i - 1], path[i], scale, 0.0);
    plan.points.emplace_back(t, path[i]);
  }
  plan.rests_at_points = true;
  plan.ok = true;
  return plan;
}

}  // namespace

Plan plan_motion(const Kinematics& k, const PlanRequest& req, CollisionModel* world, const PlannerOptions& options) {
  Plan plan;
  if (world) world->set_held(req.held);
  std::optional<Checker> check;
  if (world) check.emplace(Checker{*world, world->touches(req.start), options.check_step > 0 ? options.check_step : 0.01});
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
    if (check) {
      if (const auto touching = new_touches(*world, ik.q, check->allowed); !touching.empty()) {
        plan.error = "the goal puts " + describe(touching);
        return plan;
      }
      if (!check->segment_clear(req.start, ik.q)) return plan_around(k, req, *check, plan, scale, options);
      plan.how = "direct";
    }
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
    if (check && !check->segment_clear(prev, ik.q)) {
      const auto touching = new_touches(*world, ik.q, check->allowed);
      plan.error = "along the line, waypoint " + std::to_string(i) + " of " + std::to_string(n) + ": it puts " +
                   (touching.empty() ? std::string("the arm into something on the way there") : describe(touching));
      return plan;
    }
    t += segment_ns(k, prev, ik.q, scale, (dist / n) / (kCartesianSpeed * scale * 2));
    plan.points.emplace_back(t, ik.q);
    prev = ik.q;
    plan.position_error = ik.position_error;
    plan.orientation_error = ik.orientation_error;
  }
  plan.goal = prev;
  plan.how = check ? "line" : "";
  plan.ok = true;
  return plan;
}

}  // namespace skillbus::motion
