// Motion around obstacles in the demo scene (a post between the table and the bin): the
// straight joint move from over the table to over the bin runs into the post; the planner
// goes around it, reproducibly; a goal or a line into the post fails naming it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "skillbus/motion/collision.hpp"
#include "skillbus/motion/ik.hpp"
#include "skillbus/motion/planner.hpp"
#include "demo_arm.hpp"

using namespace skillbus;
using namespace skillbus::motion;
using namespace skillbus::motion::test;

namespace {

// The arm over the red cube (where the demo lifts it from), holding it.
Eigen::VectorXd over_red() {
  const IkResult r = solve_ik(kin(), top_down(0.4, 0.15, 0.525), home());
  EXPECT_TRUE(r.ok) << r.error;
  return r.q;
}

PlanRequest to_bin() {
  PlanRequest req;
  req.start = over_red();
  req.target = top_down(0.0, 0.6, 0.45);
  req.held = Eigen::Vector3d::Constant(0.05);
  return req;
}

// Every state of the trajectory as the follower plays it (straight joint segments between
// rest points), every `step` rad: what it touches of the scene's obstacles, exactly (no
// margin).
std::vector<std::string> obstacle_touches(const Plan& plan, const Eigen::VectorXd& start, const Eigen::Vector3d& held) {
  CollisionOptions exact;
  exact.obstacle_margin = 0;
  CollisionModel world(demo_scene(), "", exact);
  world.set_held(held);
  std::vector<std::string> out;
  Eigen::VectorXd prev = start;
  for (const auto& [t, q] : plan.points) {
    const int n = std::max(1, static_cast<int>(std::ceil((q - prev).cwiseAbs().maxCoeff() / 0.002)));
    for (int i = 1; i <= n; ++i)
      for (const auto& touch : world.touches(prev + (q - prev) * (static_cast<double>(i) / n)))
        if (touch.obstacle) out.push_back(touch.part + " on " + touch.body);
    prev = q;
  }
  return out;
}

}  // namespace

TEST(Collision, TheStraightMoveToTheBinRunsIntoThePost) {
  // The case the planner must solve: without a collision model the move is one straight
  // joint segment, and it sweeps the held cube or the arm through the post.
  const PlanRequest req = to_bin();
  const Plan straight = plan_motion(kin(), req);
  ASSERT_TRUE(straight.ok) << straight.error;
  ASSERT_EQ(straight.points.size(), 1u);
  EXPECT_FALSE(obstacle_touches(straight, req.start, req.held).empty());
}

TEST(Collision, TheMoveToTheBinGoesAroundThePost) {
  CollisionModel world(demo_scene());
  const PlanRequest req = to_bin();
  const Plan plan = plan_motion(kin(), req, &world);
  ASSERT_TRUE(plan.ok) << plan.error;
  EXPECT_EQ(plan.how, "around");
  EXPECT_TRUE(plan.rests_at_points);
  EXPECT_GE(plan.points.size(), 2u);
  EXPECT_GT(plan.iterations, 0);
  EXPECT_TRUE(obstacle_touches(plan, req.start, req.held).empty());
  const auto [pe, oe] = pose_error(kin(), plan.points.back().second, req.target);
  EXPECT_LT(pe, 1e-3);
  EXPECT_LT(oe, 1e-2);
  // Within the joint limits at each point, and timed within the velocity limits.
  Eigen::VectorXd prev = req.start;
  int64_t t_prev = 0;
  for (const auto& [t, q] : plan.points) {
    for (size_t j = 0; j < kin().joints().size(); ++j) {
      const auto i = static_cast<Eigen::Index>(j);
      EXPECT_GE(q[i], kin().joints()[j].lower - 1e-9);
      EXPECT_LE(q[i], kin().joints()[j].upper + 1e-9);
      EXPECT_LE(1.5 * std::abs(q[i] - prev[i]) / ((t - t_prev) * 1e-9), 0.5 * kin().joints()[j].velocity + 1e-9);
    }
    prev = q;
    t_prev = t;
  }
}

TEST(Collision, TheSameRequestGetsTheSamePath) {
  CollisionModel a(demo_scene()), b(demo_scene());
  const PlanRequest req = to_bin();
  const Plan first = plan_motion(kin(), req, &a);
  plan_motion(kin(), to_bin(), &a);  // another request in between changes nothing
  const Plan again = plan_motion(kin(), req, &a), fresh = plan_motion(kin(), req, &b);
  ASSERT_TRUE(first.ok && again.ok && fresh.ok);
  for (const Plan* p : {&again, &fresh}) {
    ASSERT_EQ(p->points.size(), first.points.size());
    EXPECT_EQ(p->iterations, first.iterations);
    for (size_t i = 0; i < first.points.size(); ++i) {
      EXPECT_EQ(p->points[i].first, first.points[i].first);
      EXPECT_EQ(p->points[i].second, first.points[i].second);  // bit for bit
    }
  }
}

TEST(Collision, AGoalInsideTheObstacleFailsNamingIt) {
  CollisionModel world(demo_scene());
  PlanRequest req;
  req.start = over_red();
  req.target = top_down(0.3, 0.5, 0.45);  // the post's middle
  const Plan plan = plan_motion(kin(), req, &world);
  ASSERT_FALSE(plan.ok);
  EXPECT_NE(plan.error.find("the goal puts"), std::string::npos) << plan.error;
  EXPECT_NE(plan.error.find("into 'post' (an obstacle)"), std::string::npos) << plan.error;
  EXPECT_TRUE(plan.points.empty());
}

TEST(Collision, ALineThroughTheObstacleFailsNamingIt) {
  CollisionModel world(demo_scene());
  PlanRequest req;
  const IkResult start = solve_ik(kin(), top_down(0.3, 0.3, 0.45), home());
  ASSERT_TRUE(start.ok) << start.error;
  req.start = start.q;
  req.target = top_down(0.3, 0.7, 0.45);
  req.cartesian = true;
  const Plan plan = plan_motion(kin(), req, &world);
  ASSERT_FALSE(plan.ok);
  EXPECT_NE(plan.error.find("along the line, waypoint"), std::string::npos) << plan.error;
  EXPECT_NE(plan.error.find("'post'"), std::string::npos) << plan.error;
}

TEST(Collision, ASearchOutOfIterationsFailsNamingWhatIsInTheWay) {
  CollisionModel world(demo_scene());
  PlannerOptions tight;
  tight.max_iterations = 1;
  const Plan plan = plan_motion(kin(), to_bin(), &world, tight);
  ASSERT_FALSE(plan.ok);
  EXPECT_NE(plan.error.find("no path around"), std::string::npos) << plan.error;
  EXPECT_NE(plan.error.find("'post'"), std::string::npos) << plan.error;
  EXPECT_NE(plan.error.find("within 1 iterations"), std::string::npos) << plan.error;
}

TEST(Collision, ContactsTheMoveStartsInMayEndButNoneMayBegin) {
  // Just grasped: the held cube still rests on the table. Lifting it is allowed; pushing
  // it down into the table is not.
  CollisionModel world(demo_scene());
  const IkResult at_cube = solve_ik(kin(), top_down(0.4, 0.15, 0.42), home());  // 5 mm into the table
  ASSERT_TRUE(at_cube.ok);
  world.set_held(Eigen::Vector3d::Constant(0.05));
  const auto touching = world.touches(at_cube.q);
  ASSERT_FALSE(touching.empty());
  EXPECT_EQ(touching.front().part, "held object");
  EXPECT_EQ(touching.front().body, "table");
  PlanRequest lift;
  lift.start = at_cube.q;
  lift.target = top_down(0.4, 0.15, 0.53);
  lift.cartesian = true;
  lift.held = Eigen::Vector3d::Constant(0.05);
  const Plan up = plan_motion(kin(), lift, &world);
  EXPECT_TRUE(up.ok) << up.error;
  // A move that starts clear may not end in the table.
  PlanRequest down = lift;
  down.start = up.goal;
  down.target = top_down(0.4, 0.15, 0.40);
  const Plan into = plan_motion(kin(), down, &world);
  ASSERT_FALSE(into.ok);
  EXPECT_NE(into.error.find("held object into 'table'"), std::string::npos) << into.error;
}

TEST(Collision, TheHeldBoxSetAgainIsTheSameAndAnotherReplacesIt) {
  // (Every plan sets it; the same box again keeps the collision objects made for it.)
  CollisionModel world(demo_scene());
  const IkResult at_cube = solve_ik(kin(), top_down(0.4, 0.15, 0.42), home());  // the box 5 mm into the table
  ASSERT_TRUE(at_cube.ok);
  const auto held_touches = [&] {
    for (const auto& t : world.touches(at_cube.q))
      if (t.part == "held object") return true;
    return false;
  };
  EXPECT_FALSE(held_touches());
  world.set_held(Eigen::Vector3d::Constant(0.05));
  EXPECT_TRUE(held_touches());
  EXPECT_FALSE(world.clear(at_cube.q, {}));
  world.set_held(Eigen::Vector3d::Constant(0.05));
  EXPECT_TRUE(held_touches());
  EXPECT_FALSE(world.clear(at_cube.q, {}));
  world.set_held(Eigen::Vector3d::Constant(0.01));  // a smaller box: above the table
  EXPECT_FALSE(held_touches());
  world.set_held(Eigen::Vector3d::Zero());
  EXPECT_FALSE(held_touches());
  EXPECT_EQ(world.clear(at_cube.q, {}), world.touches(at_cube.q).empty());
  world.set_held(Eigen::Vector3d::Constant(0.05));
  EXPECT_TRUE(held_touches());
}

namespace {

// The demo scene without its post, and the post as an occupancy map would hold it: every
// 1 cm voxel of its volume (what a camera all around it would have seen).
scene::Scene scene_without_obstacles() {
  scene::Scene s = demo_scene();
  s.fixtures.erase(std::remove_if(s.fixtures.begin(), s.fixtures.end(), [](const auto& f) { return f.obstacle; }),
                   s.fixtures.end());
  return s;
}

std::vector<Eigen::Vector3d> post_voxels() {
  std::vector<Eigen::Vector3d> out;
  for (int x = 0; x < 10; ++x)
    for (int y = 0; y < 10; ++y)
      for (int z = 0; z < 60; ++z) out.emplace_back(0.255 + 0.01 * x, 0.455 + 0.01 * y, 0.005 + 0.01 * z);
  return out;
}

}  // namespace

TEST(Collision, WhatTheMapHoldsIsAvoidedLikeAKnownObstacle) {
  const scene::Scene bare = scene_without_obstacles();
  CollisionModel world(bare);
  const PlanRequest req = to_bin();
  const Plan without = plan_motion(kin(), req, &world);
  ASSERT_TRUE(without.ok) << without.error;
  EXPECT_EQ(without.how, "direct");  // nothing known in the way
  world.set_map(post_voxels(), 0.01);
  EXPECT_EQ(world.map_voxels(), 6000u);
  const Plan with = plan_motion(kin(), req, &world);
  ASSERT_TRUE(with.ok) << with.error;
  EXPECT_EQ(with.how, "around");
  EXPECT_TRUE(obstacle_touches(with, req.start, req.held).empty());  // checked against the real post
  // A goal in the mapped space fails naming the map.
  PlanRequest into = req;
  into.target = top_down(0.3, 0.5, 0.45);
  const Plan bad = plan_motion(kin(), into, &world);
  ASSERT_FALSE(bad.ok);
  EXPECT_NE(bad.error.find("into 'the occupancy map'"), std::string::npos) << bad.error;
  // Without the map again: the straight move.
  world.set_map({}, 0.01);
  EXPECT_EQ(plan_motion(kin(), req, &world).how, "direct");
}

TEST(Collision, MapVoxelsAroundAPointCanBeLeftOut) {
  CollisionModel world(scene_without_obstacles());
  world.set_map(post_voxels(), 0.01);
  world.clear_map_around(Eigen::Vector3d(0.3, 0.5, 0.3), 0.05);
  EXPECT_LT(world.map_voxels(), 6000u);
  EXPECT_GT(world.map_voxels(), 0u);
}

namespace {

// How many of `states` clear() and DART's group-against-group check answer alike, and how
// many of them are clear.
struct Agreement {
  int same = 0, clear = 0, total = 0;
};

Agreement compare(const CollisionModel& world, const std::vector<Eigen::VectorXd>& states,
                  const std::vector<Touch>& allowed = {}) {
  Agreement a;
  for (const auto& q : states) {
    const bool pairwise = world.clear(q, allowed);
    const bool groups = world.clear_by_groups(q, allowed);
    a.same += pairwise == groups;
    a.clear += pairwise;
    ++a.total;
  }
  return a;
}

// Seeded states: anywhere within the joint limits, and along the straight joint moves
// between the demo's poses (the table, the post and the bin close by, touching or nearly).
std::vector<Eigen::VectorXd> sample_states() {
  std::vector<Eigen::VectorXd> out;
  std::mt19937 rng(20261204);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto& joints = kin().joints();
  for (int i = 0; i < 400; ++i) {
    Eigen::VectorXd q(static_cast<Eigen::Index>(joints.size()));
    for (size_t j = 0; j < joints.size(); ++j)
      q[static_cast<Eigen::Index>(j)] = joints[j].lower + u(rng) * (joints[j].upper - joints[j].lower);
    out.push_back(q);
  }
  std::vector<Eigen::VectorXd> poses = {home(), over_red()};
  for (const auto& t : {top_down(0.4, 0.15, 0.40), top_down(0.0, 0.6, 0.45), top_down(0.3, 0.5, 0.45),
                        top_down(0.2, 0.45, 0.3), top_down(0.0, 0.6, 0.2)}) {
    const IkResult r = solve_ik(kin(), t, home());
    if (r.ok) poses.push_back(r.q);
  }
  for (size_t a = 0; a < poses.size(); ++a)
    for (size_t b = a + 1; b < poses.size(); ++b)
      for (int i = 0; i <= 60; ++i) out.push_back(poses[a] + (poses[b] - poses[a]) * (i / 60.0));
  return out;
}

}  // namespace

TEST(Collision, ThePairwiseCheckAnswersAsDartsGroups) {
  // clear() checks pair by pair, without DART's broad phase: on every state it must give
  // DART's answer, with and without a held object, with a map, and with allowed contacts.
  const auto states = sample_states();
  CollisionModel world(demo_scene());
  Agreement bare = compare(world, states);
  EXPECT_EQ(bare.same, bare.total);
  EXPECT_GT(bare.clear, bare.total / 10);  // both answers occur
  EXPECT_LT(bare.clear, bare.total - bare.total / 10);

  world.set_held(Eigen::Vector3d::Constant(0.05));
  const Agreement held = compare(world, states);
  EXPECT_EQ(held.same, held.total);
  EXPECT_LT(held.clear, bare.clear);  // the cube makes some states touch

  // Allowed: the contacts of a grasp still on the table.
  const IkResult at_cube = solve_ik(kin(), top_down(0.4, 0.15, 0.42), home());
  ASSERT_TRUE(at_cube.ok);
  const auto touching = world.touches(at_cube.q);
  ASSERT_FALSE(touching.empty());
  const Agreement allowed = compare(world, states, touching);
  EXPECT_EQ(allowed.same, allowed.total);
  EXPECT_GT(allowed.clear, held.clear);
  EXPECT_FALSE(world.clear(at_cube.q));
  EXPECT_TRUE(world.clear(at_cube.q, touching));
  // Back to no allowed contacts, after the other check: the pairs are worked out again.
  EXPECT_FALSE(world.clear_by_groups(at_cube.q, touching) && world.clear(at_cube.q));

  CollisionModel mapped(scene_without_obstacles());
  const Agreement before = compare(mapped, states);
  mapped.set_map(post_voxels(), 0.01);
  const Agreement with_map = compare(mapped, states);
  EXPECT_EQ(with_map.same, with_map.total);
  EXPECT_LT(with_map.clear, before.clear);  // the mapped post is in the way of some
  mapped.set_held(Eigen::Vector3d::Constant(0.05));
  const Agreement map_held = compare(mapped, states);
  EXPECT_EQ(map_held.same, map_held.total);
}
