// The physics server's controllers without DART: the arm's computed-torque PID (commands,
// trajectory playback, the bounded integral) and the coupled, force-limited fingers
// (command checks, the ramp, grip mode, centring), each also closed around an ideal plant.
#include <gtest/gtest.h>

#include <cmath>

#include "skillbus/sim/arm_controller.hpp"
#include "skillbus/sim/finger_controller.hpp"

using namespace skillbus::sim;

namespace {

constexpr int64_t kStepNs = 2'000'000;  // the demo scene's 2 ms step
constexpr double kDt = kStepNs * 1e-9;

ArmController two_joint_arm(std::vector<double> at = {0.0, 0.5}) {
  return ArmController({"shoulder", "elbow"}, {{-2, 2, 1.0}, {-1, 1, 2.0}}, std::move(at), kStepNs);
}

ArmCommand arm_command(std::vector<std::string> joints, std::vector<Waypoint> points, std::string id = "c1") {
  ArmCommand c;
  c.id = std::move(id);
  c.joints = std::move(joints);
  c.points = std::move(points);
  return c;
}

Waypoint at(double t_s, std::vector<double> q) { return Waypoint{static_cast<int64_t>(t_s * 1e9), std::move(q), {}}; }

GripperCommand gripper(double width, double speed = 0.1, double force = 10.0) {
  GripperCommand c;
  c.id = "g";
  c.width = width;
  c.speed = speed;
  c.force_limit = force;
  return c;
}

const FingerLimits kFingers{0.04, 40.0, 0.1};
constexpr double kFingerMass = 0.05;  // kg

}  // namespace

// ---------------------------------------------------------------- arm

TEST(ArmController, HoldsWhereItStartsWithoutEffort) {
  ArmController arm = two_joint_arm();
  EXPECT_FALSE(arm.moving());
  EXPECT_EQ(arm.reference_positions(0), (std::vector<double>{0.0, 0.5}));
  EXPECT_EQ(arm.accelerations(0, {0.0, 0.5}, {0.0, 0.0}), (std::vector<double>{0.0, 0.0}));
}

TEST(ArmController, PidOnTheErrorWithTheIntegralBounded) {
  ArmController arm = two_joint_arm();
  // 0.01 rad short of the target on the first joint, moving away at 0.1 rad/s.
  const std::vector<double> acc = arm.accelerations(0, {-0.01, 0.5}, {-0.1, 0.0});
  const double e = 0.01;
  EXPECT_DOUBLE_EQ(acc[0], ArmController::kKp * e + ArmController::kKd * 0.1 + ArmController::kKi * e * kDt);
  EXPECT_DOUBLE_EQ(acc[1], 0.0);
  // A large error held for long: the integral stops at its limit.
  std::vector<double> last;
  for (int i = 0; i < 10000; ++i) last = arm.accelerations(i, {-0.5, 0.5}, {0.0, 0.0});
  EXPECT_DOUBLE_EQ(last[0], ArmController::kKp * 0.5 + ArmController::kKi * ArmController::kIntegralLimit);
}

TEST(ArmController, RejectedCommandsNameTheProblemAndChangeNothing) {
  ArmController arm = two_joint_arm();
  EXPECT_EQ(arm.command(arm_command({}, {at(0, {})}), 0), "the command names no joints");
  EXPECT_EQ(arm.command(arm_command({"elbow"}, {}), 0), "the command has no points");
  EXPECT_EQ(arm.command(arm_command({"wrist"}, {at(0, {0.1})}), 0),
            "unknown arm joint 'wrist' (the arm has shoulder, elbow)");
  EXPECT_EQ(arm.command(arm_command({"elbow", "elbow"}, {at(0, {0.1, 0.1})}), 0), "joint 'elbow' is named twice");
  EXPECT_EQ(arm.command(arm_command({"elbow"}, {at(0, {0.1, 0.2})}), 0), "point 0 has 2 positions for 1 joints");
  EXPECT_NE(arm.command(arm_command({"elbow"}, {at(0, {3.0})}), 0).find("outside its limits"), std::string::npos);
  EXPECT_FALSE(arm.moving());
  EXPECT_EQ(arm.command_id(), "");
  EXPECT_EQ(arm.reference_positions(100), (std::vector<double>{0.0, 0.5}));
}

TEST(ArmController, PlaysATrajectoryThenHoldsItsEnd) {
  ArmController arm = two_joint_arm();
  // Only the shoulder is named: the elbow keeps its target. Starts at step 10.
  ASSERT_EQ(arm.command(arm_command({"shoulder"}, {at(0, {1.0})}, "move-1"), 10), "");
  EXPECT_TRUE(arm.moving());
  EXPECT_EQ(arm.command_id(), "move-1");
  EXPECT_EQ(arm.reference_positions(10), (std::vector<double>{0.0, 0.5}));
  // A minimum-jerk move of 1 rad at 1 rad/s takes 1.875 s: 937.5 steps of 2 ms.
  const std::vector<double> mid = arm.reference_positions(10 + 469);
  EXPECT_NEAR(mid[0], 0.5, 0.01);
  EXPECT_DOUBLE_EQ(mid[1], 0.5);
  arm.finish_step(10 + 900);
  EXPECT_TRUE(arm.moving());
  arm.finish_step(10 + 938);
  EXPECT_FALSE(arm.moving());
  EXPECT_EQ(arm.command_id(), "move-1");
  EXPECT_EQ(arm.reference_positions(5000), (std::vector<double>{1.0, 0.5}));
}

TEST(ArmController, ANewCommandStartsFromTheCurrentReference) {
  ArmController arm = two_joint_arm();
  ASSERT_EQ(arm.command(arm_command({"shoulder"}, {at(0, {1.0})}), 0), "");
  const std::vector<double> now = arm.reference_positions(400);
  ASSERT_EQ(arm.command(arm_command({"elbow"}, {at(0.5, {0.0})}, "c2"), 400), "");
  EXPECT_EQ(arm.reference_positions(400), now);  // no jump
  arm.finish_step(400 + 250);
  EXPECT_FALSE(arm.moving());
  EXPECT_EQ(arm.reference_positions(1000), (std::vector<double>{now[0], 0.0}));  // the shoulder stopped where it was
}

TEST(ArmController, TracksWithAnExactModel) {
  // Computed torque with an exact model leaves a double integrator per joint: q'' = acc.
  ArmController arm = two_joint_arm();
  std::vector<double> q{0.0, 0.5}, dq{0.0, 0.0};
  ASSERT_EQ(arm.command(arm_command({"shoulder", "elbow"}, {at(0, {1.0, -0.5})}), 0), "");
  double worst = 0;
  int64_t step = 0;
  for (; step < 2000; ++step) {
    const std::vector<double> acc = arm.accelerations(step, q, dq);
    const std::vector<double> want = arm.reference_positions(step);
    for (size_t k = 0; k < 2; ++k) {
      worst = std::max(worst, std::abs(want[k] - q[k]));
      dq[k] += acc[k] * kDt;
      q[k] += dq[k] * kDt;
    }
    arm.finish_step(step + 1);
  }
  EXPECT_FALSE(arm.moving());
  EXPECT_LT(worst, 2e-3);
  EXPECT_NEAR(q[0], 1.0, 1e-4);
  EXPECT_NEAR(q[1], -0.5, 1e-4);
}

TEST(ArmController, JointForceAddsDampingWithinTheLimits) {
  EXPECT_DOUBLE_EQ(ArmController::joint_force(10.0, 0.5, 2.0, -50, 50), 11.0);
  EXPECT_DOUBLE_EQ(ArmController::joint_force(100.0, 0.0, 0.0, -50, 50), 50.0);
  EXPECT_DOUBLE_EQ(ArmController::joint_force(-100.0, 0.0, 0.0, -50, 50), -50.0);
}

// ---------------------------------------------------------------- fingers

TEST(FingerController, StartsHoldingWhereTheFingersAre) {
  FingerController f(kFingers, kFingerMass, kStepNs, 0.03);
  EXPECT_DOUBLE_EQ(f.target(), 0.03);
  EXPECT_DOUBLE_EQ(f.reference(), 0.03);
  const FingerController::Forces out = f.update(0.03, 0.03, 0, 0);
  EXPECT_DOUBLE_EQ(out.squeeze, 0.0);
  EXPECT_DOUBLE_EQ(out.centring, 0.0);
}

TEST(FingerController, RejectedCommandsNameTheProblemAndChangeNothing) {
  FingerController f(kFingers, kFingerMass, kStepNs, 0.03);
  EXPECT_EQ(f.command(gripper(std::nan("")), 0.03), "width, speed and force_limit must be finite numbers");
  EXPECT_NE(f.command(gripper(0.09), 0.03).find("width 0.090000 m is outside [0, 0.080000]"), std::string::npos);
  EXPECT_NE(f.command(gripper(0.02, 0.3), 0.03).find("speed 0.300000 m/s is outside (0, 0.200000]"), std::string::npos);
  EXPECT_NE(f.command(gripper(0.02, 0.1, 50), 0.03).find("force_limit 50.000000 N is outside (0, 40.000000]"),
            std::string::npos);
  EXPECT_NE(f.command(gripper(0.02, 0.1, 0), 0.03).find("force_limit"), std::string::npos);
  EXPECT_DOUBLE_EQ(f.target(), 0.03);
}

TEST(FingerController, TheReferenceRampsAtTheCommandedSpeed) {
  FingerController f(kFingers, kFingerMass, kStepNs, 0.04);
  ASSERT_EQ(f.command(gripper(0.0, 0.1), 0.04), "");  // close at 0.1 m/s of width: 0.05 m/s per finger
  EXPECT_DOUBLE_EQ(f.target(), 0.0);
  f.update(0.04, 0.04, 0, 0);
  EXPECT_NEAR(f.reference(), 0.04 - 0.05 * kDt, 1e-15);
  const FingerController::Forces out = f.update(0.04, 0.04, 0, 0);
  EXPECT_LT(out.squeeze, 0.0);  // closing
}

TEST(FingerController, BlockedFingersSqueezeWithExactlyTheForceLimit) {
  FingerController f(kFingers, kFingerMass, kStepNs, 0.04);
  ASSERT_EQ(f.command(gripper(0.0, 0.1, 12.5), 0.04), "");
  // An object 2 cm wide: the fingers stop at 0.01 each and stay there.
  FingerController::Forces out;
  for (int i = 0; i < 500; ++i) out = f.update(0.01, 0.01, 0, 0);
  EXPECT_TRUE(f.gripping());
  EXPECT_DOUBLE_EQ(out.squeeze, -12.5);
  // Opening again leaves grip mode and starts the ramp from where the fingers are.
  ASSERT_EQ(f.command(gripper(0.08), 0.01), "");
  EXPECT_FALSE(f.gripping());
  EXPECT_DOUBLE_EQ(f.reference(), 0.01);
}

TEST(FingerController, TheFingersAreCentred) {
  FingerController f(kFingers, kFingerMass, kStepNs, 0.03);
  // Left 2 mm further open than right: the left finger is pushed in, the right out.
  const FingerController::Forces out = f.update(0.031, 0.029, 0, 0);
  EXPECT_LT(out.centring, 0.0);
  EXPECT_DOUBLE_EQ(FingerController::finger_force(out, true, 0, 0, 0, -100, 100), out.squeeze + out.centring);
  EXPECT_DOUBLE_EQ(FingerController::finger_force(out, false, 0, 0, 0, -100, 100), out.squeeze - out.centring);
  EXPECT_DOUBLE_EQ(FingerController::finger_force(out, true, 0, 0, 0, -1e-6, 1e-6), -1e-6);  // within the limits
}

TEST(FingerController, ReachesItsTargetOnTwoFreeFingers) {
  FingerController f(kFingers, kFingerMass, kStepNs, 0.04);
  ASSERT_EQ(f.command(gripper(0.03, 0.1, 20), 0.04), "");  // to 1.5 cm each
  double ql = 0.04, qr = 0.035, vl = 0, vr = 0;           // and uneven to begin with
  for (int i = 0; i < 1000; ++i) {                         // 2 s
    const FingerController::Forces out = f.update(ql, qr, vl, vr);
    vl += FingerController::finger_force(out, true, 0, 0, vl, -40, 40) / kFingerMass * kDt;
    vr += FingerController::finger_force(out, false, 0, 0, vr, -40, 40) / kFingerMass * kDt;
    ql += vl * kDt;
    qr += vr * kDt;
  }
  EXPECT_NEAR(0.5 * (ql + qr), 0.015, 1e-4);
  EXPECT_NEAR(ql - qr, 0.0, 1e-4);
  EXPECT_FALSE(f.gripping());
}
