#include "skillbus/motion/ik.hpp"

#include <ceres/ceres.h>

#include <cmath>
#include <sstream>

namespace skillbus::motion {

namespace {

constexpr double kOrientationWeight = 0.3;  // 1 rad of orientation counts as 0.3 m of position

Eigen::Vector3d rotation_error(const Eigen::Matrix3d& R, const Eigen::Matrix3d& target) {
  const Eigen::AngleAxisd aa(R * target.transpose());  // world-frame rotation from target to R
  return aa.angle() * aa.axis();
}

class PoseCost : public ceres::CostFunction {
 public:
  PoseCost(const Kinematics& k, const Eigen::Isometry3d& target) : k_(k), target_(target) {
    set_num_residuals(6);
    mutable_parameter_block_sizes()->push_back(static_cast<int>(k.joints().size()));
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const auto n = static_cast<Eigen::Index>(k_.joints().size());
    const Eigen::VectorXd q = Eigen::Map<const Eigen::VectorXd>(parameters[0], n);
    const Eigen::Isometry3d T = k_.tool_pose(q);
    Eigen::Map<Eigen::Matrix<double, 6, 1>> r(residuals);
    r.head<3>() = T.translation() - target_.translation();
    r.tail<3>() = kOrientationWeight * rotation_error(T.linear(), target_.linear());
    if (jacobians && jacobians[0]) {
      Eigen::MatrixXd J = k_.jacobian(q);  // linear; angular (world)
      J.bottomRows<3>() *= kOrientationWeight;
      Eigen::Map<Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::RowMajor>>(jacobians[0], 6, n) = J;
    }
    return true;
  }

 private:
  const Kinematics& k_;
  Eigen::Isometry3d target_;
};

// Seeds after the current joints: the current ones turned toward the target, then a few
// fixed arm shapes (elbow up, elbow down, wrist flipped) in that direction. Fixed, so the
// search is the same on every run.
std::vector<Eigen::VectorXd> seeds(const Kinematics& k, const Eigen::Isometry3d& target, const Eigen::VectorXd& q0) {
  std::vector<Eigen::VectorXd> out{q0};
  // The target's direction seen from the robot's base (an arm that does not stand at the
  // world's origin, or is turned, turns its first joint by the direction from itself).
  const Eigen::Vector3d from_base = k.base().linear().transpose() * (target.translation() - k.base().translation());
  const double yaw = std::atan2(from_base.y(), from_base.x());
  Eigen::VectorXd turned = q0;
  turned[0] = yaw;
  out.push_back(turned);
  const double shapes[][6] = {{0, 0.3, 1.4, 0, 1.4, 0}, {0, 0.8, 0.9, 0, 1.4, 0}, {0, -0.3, 2.0, 0, 1.4, 0},
                              {0, 0.3, 1.4, 3.0, -1.4, 0}, {0, 0.5, -1.2, 0, -0.8, 0}};
  for (const auto& s : shapes) {
    Eigen::VectorXd q = q0;
    for (Eigen::Index i = 0; i < q.size() && i < 6; ++i) q[i] = s[i];
    q[0] = yaw;
    out.push_back(q);
  }
  for (auto& q : out)
    for (size_t i = 0; i < k.joints().size(); ++i)
      q[static_cast<Eigen::Index>(i)] = std::clamp(q[static_cast<Eigen::Index>(i)], k.joints()[i].lower, k.joints()[i].upper);
  return out;
}

}  // namespace

std::pair<double, double> pose_error(const Kinematics& k, const Eigen::VectorXd& q, const Eigen::Isometry3d& target) {
  const Eigen::Isometry3d T = k.tool_pose(q);
  return {(T.translation() - target.translation()).norm(), rotation_error(T.linear(), target.linear()).norm()};
}

IkResult solve_ik(const Kinematics& k, const Eigen::Isometry3d& target, const Eigen::VectorXd& seed,
                  const IkOptions& opt) {
  IkResult best;
  double best_cost = 1e300;
  const auto n = static_cast<int>(k.joints().size());
  for (const Eigen::VectorXd& s : seeds(k, target, seed)) {
    ++best.seeds_tried;
    std::vector<double> q(s.data(), s.data() + s.size());
    ceres::Problem problem;
    problem.AddResidualBlock(new PoseCost(k, target), nullptr, q.data());
    for (int i = 0; i < n; ++i) {
      problem.SetParameterLowerBound(q.data(), i, k.joints()[static_cast<size_t>(i)].lower);
      problem.SetParameterUpperBound(q.data(), i, k.joints()[static_cast<size_t>(i)].upper);
    }
    ceres::Solver::Options so;
    so.linear_solver_type = ceres::DENSE_QR;
    so.max_num_iterations = opt.max_iterations;
    so.function_tolerance = 1e-14;
    so.gradient_tolerance = 1e-14;
    so.parameter_tolerance = 1e-12;
    so.num_threads = 1;  // the same answer every run
    so.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    const Eigen::VectorXd qs = Eigen::Map<Eigen::VectorXd>(q.data(), n);
    const auto [pe, oe] = pose_error(k, qs, target);
    const double cost = pe + kOrientationWeight * oe;
    if (cost < best_cost) {
      best_cost = cost;
      best.q = qs;
      best.position_error = pe;
      best.orientation_error = oe;
    }
    if (pe <= opt.position_tolerance && oe <= opt.orientation_tolerance) {
      best.ok = true;
      return best;
    }
  }
  std::ostringstream why;
  why.precision(3);
  why << "unreachable: no joint solution within the limits puts the tool at (" << target.translation().x() << ", "
      << target.translation().y() << ", " << target.translation().z() << "); the best of " << best.seeds_tried
      << " seeds is " << best.position_error * 1000 << " mm and " << best.orientation_error << " rad away";
  best.error = why.str();
  return best;
}

}  // namespace skillbus::motion
