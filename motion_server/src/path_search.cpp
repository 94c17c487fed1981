#include "path_search.hpp"

#include <ompl/base/MotionValidator.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/datastructures/NearestNeighborsLinear.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>

namespace skillbus::motion {

namespace ob = ompl::base;
namespace og = ompl::geometric;

namespace {

Eigen::VectorXd to_vector(const ob::State* s, Eigen::Index n) {
  const auto* v = s->as<ob::RealVectorStateSpace::StateType>();
  Eigen::VectorXd q(n);
  for (Eigen::Index i = 0; i < n; ++i) q[i] = v->values[i];
  return q;
}

// OMPL's default sampler draws its seed from a process-wide sequence: the same request
// would get another path on its second asking. This one starts from the search's seed.
class SeededSampler : public ob::RealVectorStateSampler {
 public:
  SeededSampler(const ob::StateSpace* space, uint32_t seed) : ob::RealVectorStateSampler(space) {
    rng_.setLocalSeed(seed);
  }
};

// Motions are checked by the caller's segment test (the same one the shortcut uses).
class SegmentValidator : public ob::MotionValidator {
 public:
  SegmentValidator(const ob::SpaceInformationPtr& si, Eigen::Index n,
                   std::function<bool(const Eigen::VectorXd&, const Eigen::VectorXd&)> clear)
      : ob::MotionValidator(si), n_(n), clear_(std::move(clear)) {}
  bool checkMotion(const ob::State* a, const ob::State* b) const override {
    const bool ok = clear_(to_vector(a, n_), to_vector(b, n_));
    if (ok) ++valid_; else ++invalid_;
    return ok;
  }
  bool checkMotion(const ob::State* a, const ob::State* b, std::pair<ob::State*, double>& last) const override {
    // Only planners that keep partial motions ask this (RRTConnect does not): no partial.
    if (checkMotion(a, b)) return true;
    si_->copyState(last.first, a);
    last.second = 0;
    return false;
  }

 private:
  Eigen::Index n_;
  std::function<bool(const Eigen::VectorXd&, const Eigen::VectorXd&)> clear_;
};

}  // namespace

PathSearch search_path(const Eigen::VectorXd& start, const Eigen::VectorXd& goal, const Eigen::VectorXd& lower,
                       const Eigen::VectorXd& upper, const std::function<bool(const Eigen::VectorXd&)>& valid,
                       const std::function<bool(const Eigen::VectorXd&, const Eigen::VectorXd&)>& segment_clear,
                       const PathSearchOptions& options) {
  ompl::msg::setLogLevel(ompl::msg::LOG_WARN);
  const Eigen::Index n = start.size();
  auto space = std::make_shared<ob::RealVectorStateSpace>(static_cast<unsigned>(n));
  ob::RealVectorBounds bounds(static_cast<unsigned>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    bounds.setLow(static_cast<unsigned>(i), lower[i]);
    bounds.setHigh(static_cast<unsigned>(i), upper[i]);
  }
  space->setBounds(bounds);
  const uint32_t seed = options.seed;
  space->setStateSamplerAllocator(
      [seed](const ob::StateSpace* s) { return std::make_shared<SeededSampler>(s, seed); });
  auto si = std::make_shared<ob::SpaceInformation>(space);
  si->setStateValidityChecker([&](const ob::State* s) { return valid(to_vector(s, n)); });
  si->setMotionValidator(std::make_shared<SegmentValidator>(si, n, segment_clear));
  si->setup();

  ob::ScopedState<> from(space), to(space);
  for (Eigen::Index i = 0; i < n; ++i) {
    from[static_cast<unsigned>(i)] = start[i];
    to[static_cast<unsigned>(i)] = goal[i];
  }
  auto pdef = std::make_shared<ob::ProblemDefinition>(si);
  pdef->setStartAndGoalStates(from, to);

  og::RRTConnect planner(si);
  planner.setRange(options.range);
  planner.setProblemDefinition(pdef);
  // A linear nearest-neighbour search: OMPL's default (GNAT) picks pivots at random. (This
  // sets the planner up.)
  planner.setNearestNeighbors<ompl::NearestNeighborsLinear>();

  PathSearch out;
  int iterations = 0;
  const int limit = options.max_iterations;
  const ob::PlannerStatus status =
      planner.solve(ob::PlannerTerminationCondition([&] { return ++iterations > limit; }));
  out.iterations = std::min(iterations, limit);
  if (status != ob::PlannerStatus::EXACT_SOLUTION) return out;
  auto& path = *pdef->getSolutionPath()->as<og::PathGeometric>();
  for (const ob::State* s : path.getStates()) out.path.push_back(to_vector(s, n));
  out.ok = true;
  return out;
}

std::vector<Eigen::VectorXd> shortcut(const std::vector<Eigen::VectorXd>& path,
                                      const std::function<bool(const Eigen::VectorXd&, const Eigen::VectorXd&)>& segment_clear) {
  if (path.size() <= 2) return path;
  std::vector<Eigen::VectorXd> out{path.front()};
  size_t i = 0;
  while (i + 1 < path.size()) {
    size_t j = path.size() - 1;
    while (j > i + 1 && !segment_clear(path[i], path[j])) --j;
    out.push_back(path[j]);
    i = j;
  }
  return out;
}

}  // namespace skillbus::motion
