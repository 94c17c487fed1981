#include "skillbus/sim/arm_controller.hpp"

#include <algorithm>
#include <set>
#include <stdexcept>

namespace skillbus::sim {

ArmController::ArmController(std::vector<std::string> names, std::vector<JointLimits> limits,
                             std::vector<double> positions, int64_t step_ns)
    : names_(std::move(names)), limits_(std::move(limits)), step_ns_(step_ns), target_(std::move(positions)) {
  if (names_.size() != limits_.size() || names_.size() != target_.size())
    throw std::invalid_argument("ArmController: names, limits and positions differ in size");
  for (size_t k = 0; k < names_.size(); ++k) index_[names_[k]] = k;
  integral_.assign(target_.size(), 0.0);
}

std::string ArmController::command(const ArmCommand& cmd, int64_t step) {
  if (cmd.joints.empty()) return "the command names no joints";
  if (cmd.points.empty()) return "the command has no points";
  if (cmd.points.size() > 100000) return "the command has more than 100000 points";
  std::vector<size_t> idx;
  std::set<std::string> seen;
  for (const auto& j : cmd.joints) {
    auto it = index_.find(j);
    if (it == index_.end()) {
      std::string known;
      for (const auto& n : names_) known += (known.empty() ? "" : ", ") + n;
      return "unknown arm joint '" + j + "' (the arm has " + known + ")";
    }
    if (!seen.insert(j).second) return "joint '" + j + "' is named twice";
    idx.push_back(it->second);
  }
  // Expand to all arm joints: unnamed joints keep their current target.
  const std::vector<double> start = reference_positions(step);
  std::vector<Waypoint> pts;
  for (size_t k = 0; k < cmd.points.size(); ++k) {
    const Waypoint& p = cmd.points[k];
    if (p.q.size() != idx.size())
      return "point " + std::to_string(k) + " has " + std::to_string(p.q.size()) + " positions for " +
             std::to_string(idx.size()) + " joints";
    if (!p.qd.empty() && p.qd.size() != idx.size())
      return "point " + std::to_string(k) + " has " + std::to_string(p.qd.size()) + " velocities for " +
             std::to_string(idx.size()) + " joints";
    Waypoint w;
    w.t_ns = p.t_ns;
    w.q = start;
    if (!p.qd.empty()) w.qd.assign(start.size(), 0.0);
    for (size_t j = 0; j < idx.size(); ++j) {
      w.q[idx[j]] = p.q[j];
      if (!p.qd.empty()) w.qd[idx[j]] = p.qd[j];
    }
    pts.push_back(std::move(w));
  }
  try {
    traj_ = JointTrajectory(start, std::move(pts), limits_, names_);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  traj_start_step_ = step;
  id_ = cmd.id;
  return "";
}

Sample ArmController::reference(int64_t step) const {
  if (!traj_.empty()) return traj_.sample(traj_time_ns(step));
  Sample s;
  s.q = target_;
  s.qd.assign(target_.size(), 0.0);
  s.qdd.assign(target_.size(), 0.0);
  return s;
}

std::vector<double> ArmController::reference_positions(int64_t step) const {
  return traj_.empty() ? target_ : traj_.sample(traj_time_ns(step)).q;
}

std::vector<double> ArmController::accelerations(int64_t step, const std::vector<double>& q,
                                                 const std::vector<double>& dq) {
  const Sample s = reference(step);
  const std::vector<double>& qt = s.q;
  const std::vector<double>& qd = s.qd;
  const std::vector<double>& qdd = s.qdd;
  const double dt = step_ns_ * 1e-9;
  std::vector<double> acc(target_.size(), 0.0);
  for (size_t k = 0; k < target_.size(); ++k) {
    const double e = qt[k] - q[k];
    integral_[k] = std::clamp(integral_[k] + e * dt, -kIntegralLimit, kIntegralLimit);
    acc[k] = qdd[k] + kKp * e + kKd * (qd[k] - dq[k]) + kKi * integral_[k];
  }
  return acc;
}

void ArmController::finish_step(int64_t steps) {
  if (!traj_.empty() && traj_time_ns(steps) >= traj_.duration_ns()) {
    target_ = traj_.final_positions();
    traj_ = JointTrajectory();
  }
}

double ArmController::joint_force(double tau, double damping, double dq, double lower, double upper) {
  const double t = tau + damping * dq;
  return std::clamp(t, lower, upper);
}

}  // namespace skillbus::sim
