// The gripper's finger controller, without DART. The two fingers are coupled like a real
// parallel gripper's: their mean opening follows a reference that ramps to the target at
// the commanded speed, under a PID whose force is limited to the commanded force limit
// (a finger blocked by an object ends up squeezing with exactly that limit, whatever the
// gains); their difference is held at zero by a stiff PD, so a squeezed object cannot
// drift along the finger axis. Openings are per finger (half the gripper's width).
#pragma once

#include <cstdint>
#include <string>

#include "skillbus/sim/commands.hpp"

namespace skillbus::sim {

// One finger's joint limits: opening (m), force (N), speed (m/s).
struct FingerLimits {
  double upper = 0.04, effort = 40, velocity = 0.1;
};

class FingerController {
 public:
  // Critically damped at up to kMaxW rad/s, but never beyond kMaxWdt rad per step (the
  // 50 g fingers are the stiffest part of the system: at 2 ms steps 200 rad/s would go
  // unstable).
  static constexpr double kMaxW = 200.0, kMaxWdt = 0.25;
  static constexpr double kIntegralRate = 10.0;           // 1/s: Ki = Kp * rate
  static constexpr double kGripLag = 0.001, kGripStill = 0.002;  // m, m/s: blocked fingers (grip mode)
  static constexpr double kDefaultSpeed = 0.1;            // m/s of the width
  static constexpr double kDefaultForce = 20.0;           // N per finger

  FingerController() = default;
  // `mass`: a finger's (its diagonal entry of the robot's mass matrix); `step_ns`: the
  // physics step; `opening`: where the fingers are, which becomes the target.
  FingerController(const FingerLimits& limits, double mass, int64_t step_ns, double opening);

  // Validates and takes a command; `opening` is where the fingers are now (the ramp starts
  // there). Returns "" or what was wrong; a rejected command changes nothing.
  std::string command(const GripperCommand& cmd, double opening);

  struct Forces {
    double squeeze = 0;   // on both fingers, closing negative
    double centring = 0;  // on the left finger; the right one gets its opposite
  };
  // One physics step: the forces from the fingers' positions and velocities.
  Forces update(double q_left, double q_right, double dq_left, double dq_right);
  // The force a finger gets: its share of `f` plus the inverse dynamics' `tau` and its
  // viscous damping, within its force limits.
  static double finger_force(const Forces& f, bool left, double tau, double damping, double dq, double lower,
                             double upper);

  double target() const { return target_; }      // per finger opening, m
  double reference() const { return ref_; }      // the ramp toward it
  bool gripping() const { return gripping_; }    // blocked: pushing with the force limit
  const FingerLimits& limits() const { return limits_; }

 private:
  FingerLimits limits_;
  int64_t step_ns_ = 1'000'000;
  double target_ = 0.04;      // per finger opening
  double ref_ = 0.04;         // the ramp toward it
  double integral_ = 0;       // m s, of the mean opening error
  bool gripping_ = false;
  double kp_ = 0, kd_ = 0;    // from the finger mass and the step
  double speed_ = kDefaultSpeed / 2, force_ = kDefaultForce;
};

}  // namespace skillbus::sim
