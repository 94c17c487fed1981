// IK and trajectories of the demo arm: reachable poses solved within tolerance (checked
// by forward kinematics), unreachable ones reported as such, lines and timing in limits.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>

#include "skillbus/motion/ik.hpp"
#include "skillbus/motion/planner.hpp"
#include "demo_arm.hpp"

using namespace skillbus;
using namespace skillbus::motion;
using namespace skillbus::motion::test;

TEST(Ik, TheHomePoseIsTheScenesToolPose) {
  const Eigen::Isometry3d T = kin().tool_pose(home());
  // measured in the physics server: (0.4006, 0.0, 0.6508), pointing down
  EXPECT_NEAR(T.translation().x(), 0.4006, 1e-3);
  EXPECT_NEAR(T.translation().z(), 0.6508, 1e-3);
  EXPECT_NEAR((T.linear() * Eigen::Vector3d::UnitZ()).z(), -1.0, 1e-3);
}

TEST(Ik, ReachablePosesAreSolvedWithinTolerance) {
  const Eigen::Isometry3d targets[] = {
      top_down(0.5, -0.1, 0.43),  top_down(0.4, 0.15, 0.43),  top_down(0.6, 0.05, 0.43),      // the cubes
      top_down(0.5, -0.1, 0.53),  top_down(0.0, 0.6, 0.35),   top_down(0.6, 0.05, 0.53, 0.5),  // above, bin, turned
      top_down(0.35, -0.3, 0.45, -0.7)};
  for (const auto& t : targets) {
    const IkResult r = solve_ik(kin(), t, home());
    ASSERT_TRUE(r.ok) << r.error;
    const auto [pe, oe] = pose_error(kin(), r.q, t);
    EXPECT_LT(pe, 1e-3);
    EXPECT_LT(oe, 1e-2);
    for (size_t i = 0; i < kin().joints().size(); ++i) {
      EXPECT_GE(r.q[static_cast<Eigen::Index>(i)], kin().joints()[i].lower - 1e-9);
      EXPECT_LE(r.q[static_cast<Eigen::Index>(i)], kin().joints()[i].upper + 1e-9);
    }
  }
}

TEST(Ik, UnreachablePosesAreReportedAsSuch) {
  for (const auto& t : {top_down(1.5, 0.0, 0.4), top_down(0.9, 0.0, 0.05), top_down(0.2, 0.0, 1.3)}) {
    const IkResult r = solve_ik(kin(), t, home());
    EXPECT_FALSE(r.ok);
    EXPECT_NE(r.error.find("unreachable: no joint solution within the limits puts the tool at"), std::string::npos)
        << r.error;
    EXPECT_GE(r.seeds_tried, 3);
  }
}

TEST(Ik, TheSameRequestGivesBitwiseTheSameAnswer) {
  const IkResult a = solve_ik(kin(), top_down(0.45, 0.1, 0.5, 0.3), home());
  const IkResult b = solve_ik(kin(), top_down(0.45, 0.1, 0.5, 0.3), home());
  ASSERT_TRUE(a.ok);
  for (Eigen::Index i = 0; i < a.q.size(); ++i) EXPECT_EQ(a.q[i], b.q[i]);
}

TEST(Planner, AStraightDescentStaysOnTheLineWithinTheLimits) {
  const IkResult above = solve_ik(kin(), top_down(0.5, -0.1, 0.53), home());
  ASSERT_TRUE(above.ok);
  PlanRequest req;
  req.start = above.q;
  req.target = top_down(0.5, -0.1, 0.43);
  req.cartesian = true;
  const Plan p = plan_motion(kin(), req);
  ASSERT_TRUE(p.ok) << p.error;
  ASSERT_EQ(p.points.size(), 10u);  // 10 cm in 1 cm steps
  Eigen::VectorXd prev = req.start;
  int64_t prev_t = 0;
  for (const auto& [t, q] : p.points) {
    const Eigen::Vector3d x = kin().tool_pose(q).translation();
    EXPECT_NEAR(x.x(), 0.5, 1e-3);
    EXPECT_NEAR(x.y(), -0.1, 1e-3);
    ASSERT_GT(t, prev_t);
    const double dt = (t - prev_t) * 1e-9;
    for (size_t i = 0; i < kin().joints().size(); ++i) {
      const auto j = static_cast<Eigen::Index>(i);
      EXPECT_LE(std::abs(q[j] - prev[j]) / dt, 0.5 * kin().joints()[i].velocity + 1e-9);
    }
    prev = q;
    prev_t = t;
  }
  EXPECT_NEAR(kin().tool_pose(p.goal).translation().z(), 0.43, 1e-3);
}

TEST(Planner, AJointMoveIsTimedByTheSlowestJoint) {
  PlanRequest req;
  req.start = home();
  req.target = top_down(0.0, 0.6, 0.35);
  const Plan p = plan_motion(kin(), req);
  ASSERT_TRUE(p.ok) << p.error;
  ASSERT_EQ(p.points.size(), 1u);
  const double dt = p.points[0].first * 1e-9;
  for (size_t i = 0; i < kin().joints().size(); ++i) {
    const auto j = static_cast<Eigen::Index>(i);
    EXPECT_LE(1.5 * std::abs(p.goal[j] - home()[j]) / dt, 0.5 * kin().joints()[i].velocity + 1e-9);
  }
}

TEST(Planner, AnUnreachableLineFailsNamingTheWaypoint) {
  PlanRequest req;
  req.start = home();
  req.target = top_down(1.4, 0.0, 0.6);
  req.cartesian = true;
  req.step_m = 0.05;
  const Plan p = plan_motion(kin(), req);
  EXPECT_FALSE(p.ok);
  EXPECT_NE(p.error.find("along the line, waypoint"), std::string::npos) << p.error;
}

TEST(Planner, ALineOfTooManyWaypointsIsRefusedAtOnce) {
  // A step_m of 1.5e-7 m (a flipped bit in the fuzz run) asked for millions of IK solves.
  PlanRequest req;
  req.start = home();
  req.target = top_down(0.5, -0.1, 0.43);
  req.cartesian = true;
  req.step_m = 1.5e-7;
  const auto t0 = std::chrono::steady_clock::now();
  const Plan p = plan_motion(kin(), req);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::milliseconds(1000));  // (millions of solves: minutes)
  EXPECT_FALSE(p.ok);
  EXPECT_NE(p.error.find("waypoints; give a larger step_m"), std::string::npos) << p.error;
  req.step_m = 1e-300;  // (the count would overflow an int)
  EXPECT_FALSE(plan_motion(kin(), req).ok);
}
