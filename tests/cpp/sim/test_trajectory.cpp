// The arm's joint trajectories: timing by velocity limits, passing through waypoints,
// and every way a command can be wrong.
#include <gtest/gtest.h>

#include <cmath>

#include "skillbus/sim/trajectory.hpp"

using namespace skillbus::sim;

namespace {
const std::vector<JointLimits> kLimits{{-2, 2, 1.0}, {-1, 1, 2.0}};
const std::vector<std::string> kNames{"a", "b"};
Waypoint wp(double t_s, std::vector<double> q) { return Waypoint{static_cast<int64_t>(t_s * 1e9), std::move(q), {}}; }
}  // namespace

TEST(Trajectory, PositionTargetIsAMinimumJerkMoveTimedByTheSlowestJoint) {
  JointTrajectory tr({0, 0}, {wp(0, {1.0, 0.5})}, kLimits, kNames);
  // joint a: 1 rad at 1 rad/s with peak/mean 1.875 -> 1.875 s; b is faster.
  EXPECT_EQ(tr.duration_ns(), 1'875'000'000);
  const Sample mid = tr.sample(tr.duration_ns() / 2);
  EXPECT_NEAR(mid.q[0], 0.5, 1e-9);
  EXPECT_NEAR(mid.qd[0], 1.0, 1e-3);  // the peak speed is the limit
  const Sample end = tr.sample(tr.duration_ns());
  EXPECT_DOUBLE_EQ(end.q[0], 1.0);
  EXPECT_DOUBLE_EQ(end.qd[0], 0.0);
  // never faster than the limit anywhere
  for (int64_t t = 0; t <= tr.duration_ns(); t += 10'000'000) EXPECT_LE(std::abs(tr.sample(t).qd[0]), 1.0 + 1e-6);
}

TEST(Trajectory, TinyMovesStillTakeATenthOfASecond) {
  JointTrajectory tr({0, 0}, {wp(0, {1e-6, 0})}, kLimits, kNames);
  EXPECT_EQ(tr.duration_ns(), 100'000'000);
}

TEST(Trajectory, PassesThroughEveryWaypointAtItsTime) {
  JointTrajectory tr({0, 0}, {wp(1.0, {0.5, 0.2}), wp(2.0, {1.0, -0.2}), wp(3.0, {0.2, 0.0})}, kLimits, kNames);
  EXPECT_EQ(tr.duration_ns(), 3'000'000'000);
  EXPECT_NEAR(tr.sample(1'000'000'000).q[0], 0.5, 1e-12);
  EXPECT_NEAR(tr.sample(2'000'000'000).q[1], -0.2, 1e-12);
  EXPECT_NEAR(tr.sample(3'000'000'000).q[0], 0.2, 1e-12);
  // b turns at t = 1 and t = 2: zero velocity there, so no overshoot of the waypoint
  EXPECT_NEAR(tr.sample(1'000'000'000).qd[1], 0.0, 1e-12);
  EXPECT_GT(tr.sample(1'000'000'000).qd[0], 0.0);  // a keeps going: a through-velocity
  // samples between waypoints lie between them (monotone segment)
  for (int64_t t = 0; t <= 1'000'000'000; t += 50'000'000) {
    EXPECT_GE(tr.sample(t).q[0], -1e-12);
    EXPECT_LE(tr.sample(t).q[0], 0.5 + 1e-12);
  }
}

TEST(Trajectory, RejectsWhatCannotBePlayed) {
  auto err = [](std::vector<Waypoint> pts) -> std::string {
    try {
      JointTrajectory({0, 0}, std::move(pts), kLimits, kNames);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(err({}), "the trajectory has no points");
  EXPECT_NE(err({wp(1, {3.0, 0})}).find("a target 3 at point 0 is outside its limits [-2, 2]"), std::string::npos);
  EXPECT_NE(err({wp(1, {NAN, 0})}).find("not a finite number"), std::string::npos);
  EXPECT_NE(err({wp(2, {0, 0}), wp(1, {0, 0})}).find("point 1 is not later than point 0"), std::string::npos);
  EXPECT_NE(err({wp(0.5, {1.5, 0})}).find("a would move at 3 rad/s"), std::string::npos);
  EXPECT_NE(err({wp(0, {0, 0}), wp(1, {0, 0})}).find("must start after t = 0"), std::string::npos);
  EXPECT_NE(err({wp(1, {0})}).find("point 0 has 1 positions for 2 joints"), std::string::npos);
  Waypoint fast = wp(1, {0.1, 0});
  fast.qd = {5.0, 0};
  EXPECT_NE(err({fast}).find("a velocity 5 at point 0 exceeds its limit 1"), std::string::npos);
}
