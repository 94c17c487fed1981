// The arm's joint controller, without DART: computed torque with PID on the
// mass-normalised error. It holds the joints' targets or plays a joint trajectory, and
// each physics step turns the reference and the measured joints into desired
// accelerations; the physics turns those into torques with the robot's inverse dynamics
// (tau = M(q) acc + C(q, dq) + g(q)), and joint_force() adds back the joint's damping
// within its force limits.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "skillbus/sim/commands.hpp"
#include "skillbus/sim/trajectory.hpp"

namespace skillbus::sim {

class ArmController {
 public:
  // All three closed-loop poles at -kW rad/s (Kp = 3w^2, Kd = 3w, Ki = w^3); the integral
  // takes up what the model does not know (a grasped object), bounded against wind-up.
  static constexpr double kW = 25.0;
  static constexpr double kKp = 3 * kW * kW, kKd = 3 * kW, kKi = kW * kW * kW;
  static constexpr double kIntegralLimit = 0.05;  // rad s

  ArmController() = default;
  // The arm's joints (names and limits, in order), holding `positions` (where they are);
  // `step_ns` is the physics step.
  ArmController(std::vector<std::string> names, std::vector<JointLimits> limits, std::vector<double> positions,
                int64_t step_ns);

  // Validates `cmd` and plays it from physics step `step` on, starting from the current
  // reference (joints it does not name keep theirs). Returns "" or what was wrong; a
  // rejected command changes nothing.
  std::string command(const ArmCommand& cmd, int64_t step);

  // Where the joints should be at physics step `step`: the trajectory's sample, or the
  // held targets.
  std::vector<double> reference_positions(int64_t step) const;
  // Desired joint accelerations for step `step` from the joints' positions and
  // velocities (one per arm joint, in order). Integrates the position error.
  std::vector<double> accelerations(int64_t step, const std::vector<double>& q, const std::vector<double>& dq);
  // Called with the step count after each physics step: a trajectory that has ended
  // leaves the arm holding its final positions.
  void finish_step(int64_t steps);

  // The force a joint gets: the inverse dynamics' `tau` plus its viscous damping (which
  // the physics applies against it), within its force limits.
  static double joint_force(double tau, double damping, double dq, double lower, double upper);

  bool moving() const { return !traj_.empty(); }
  const std::string& command_id() const { return id_; }  // the last accepted command's
  const std::vector<std::string>& names() const { return names_; }

 private:
  int64_t traj_time_ns(int64_t step) const { return (step - traj_start_step_) * step_ns_; }
  Sample reference(int64_t step) const;

  std::vector<std::string> names_;
  std::vector<JointLimits> limits_;
  std::map<std::string, size_t> index_;  // joint name -> index
  int64_t step_ns_ = 1'000'000;
  std::vector<double> target_;           // held when no trajectory plays
  std::vector<double> integral_;         // of the position error, rad s
  JointTrajectory traj_;
  int64_t traj_start_step_ = 0;
  std::string id_;
};

}  // namespace skillbus::sim
