#include "skillbus/sim/finger_controller.hpp"

#include <algorithm>
#include <cmath>

namespace skillbus::sim {

FingerController::FingerController(const FingerLimits& limits, double mass, int64_t step_ns, double opening)
    : limits_(limits), step_ns_(step_ns), target_(opening), ref_(opening) {
  const double w = std::min(kMaxW, kMaxWdt / (step_ns * 1e-9));
  kp_ = mass * w * w;
  kd_ = 2 * mass * w;
  speed_ = kDefaultSpeed / 2;
  force_ = std::min(kDefaultForce, limits_.effort);
}

std::string FingerController::command(const GripperCommand& cmd, double opening) {
  auto bad = [](double v) { return !std::isfinite(v); };
  if (bad(cmd.width) || bad(cmd.speed) || bad(cmd.force_limit)) return "width, speed and force_limit must be finite numbers";
  const double max_width = 2 * limits_.upper;
  if (cmd.width < 0 || cmd.width > max_width + 1e-9)
    return "width " + std::to_string(cmd.width) + " m is outside [0, " + std::to_string(max_width) + "]";
  if (cmd.speed <= 0 || cmd.speed > 2 * limits_.velocity + 1e-9)
    return "speed " + std::to_string(cmd.speed) + " m/s is outside (0, " + std::to_string(2 * limits_.velocity) + "]";
  if (cmd.force_limit <= 0 || cmd.force_limit > limits_.effort + 1e-9)
    return "force_limit " + std::to_string(cmd.force_limit) + " N is outside (0, " + std::to_string(limits_.effort) + "]";
  target_ = cmd.width / 2;
  speed_ = cmd.speed / 2;
  force_ = cmd.force_limit;
  integral_ = 0;  // a new command starts without the last one's wind-up
  gripping_ = false;
  // ... and from where the fingers are: after a grip the reference has run on to the
  // closed position, and an opening must not first wait for it to come back.
  ref_ = opening;
  return "";
}

FingerController::Forces FingerController::update(double q_left, double q_right, double dq_left, double dq_right) {
  const double dt = step_ns_ * 1e-9;
  const double delta = target_ - ref_;
  const double max_step = speed_ * dt;
  ref_ += std::clamp(delta, -max_step, max_step);
  const double ref_vel = std::abs(delta) > max_step ? (delta > 0 ? speed_ : -speed_) : 0.0;
  const double mean = 0.5 * (q_left + q_right), mean_vel = 0.5 * (dq_left + dq_right);
  const double diff = 0.5 * (q_left - q_right), diff_vel = 0.5 * (dq_left - dq_right);
  const double e = ref_ - mean;
  const double ki = kp_ * kIntegralRate;
  integral_ = std::clamp(integral_ + e * dt, -force_ / ki, force_ / ki);
  // Grip mode, as a gripper's firmware does it: fingers that stop short of where they
  // should be (1 mm behind the reference and still) are blocked by something, and push
  // with the force limit itself at once, instead of letting the position loop wind up
  // to it. They leave grip mode when they move again or get a new command.
  if (!gripping_ && std::abs(e) > kGripLag && std::abs(mean_vel) < kGripStill) gripping_ = true;
  if (gripping_ && (std::abs(mean_vel) > 4 * kGripStill || std::abs(e) < kGripLag / 2)) gripping_ = false;
  Forces f;
  f.squeeze = gripping_ ? (e > 0 ? force_ : -force_)
                        : std::clamp(kp_ * e + kd_ * (ref_vel - mean_vel) + ki * integral_, -force_, force_);
  f.centring = -kp_ * diff - kd_ * diff_vel;
  return f;
}

double FingerController::finger_force(const Forces& f, bool left, double tau, double damping, double dq, double lower,
                                      double upper) {
  const double v = f.squeeze + (left ? f.centring : -f.centring) + tau + damping * dq;
  return std::clamp(v, lower, upper);
}

}  // namespace skillbus::sim
