// motion_server: arm motion for the skills, over RPC (area MOTION). See README.md.
//
// Reads: SB_MOTION_REQ (plan: motion_request_t). Writes: SB_MOTION_REP (motion_plan_t).
// Not a lockstep participant: it holds no state, and the same request always gets the
// same answer (Ceres single-threaded, fixed seeds; the path search seeded per request and
// bounded in iterations), so skills may call it from a tick.
#include <cmath>
#include <cstdio>

#include "skillbus/apps/cli.hpp"
#include "skillbus/apps/lifecycle.hpp"
#include "skillbus/apps/summary.hpp"
#include "skillbus/auth.hpp"
#include "skillbus/bus.hpp"
#include "skillbus/log.hpp"
#include "skillbus/motion/planner.hpp"
#include "skillbus/rpc.hpp"
#include "skillbus_msgs/motion_plan_t.hpp"
#include "skillbus_msgs/map_query_t.hpp"
#include "skillbus_msgs/map_reply_t.hpp"
#include "skillbus_msgs/motion_request_t.hpp"

using namespace skillbus;

namespace {
// The occupancy map's occupied voxels within the arm's reach (a box around its base), as
// of the asker's frame, from the map server (RPC area MAP) on a bus of their own: waiting
// for the map must not dispatch another motion request into this one.
class MapSource {
 public:
  MapSource(std::unique_ptr<Bus> bus, const motion::Kinematics& k, double reach)
      : bus_(std::move(bus)), rpc_(*bus_, "MAP", "motion_server") {
    const Eigen::Vector3d base = k.base().translation();
    for (int i = 0; i < 3; ++i) {
      lo_[i] = base[i] - reach;
      hi_[i] = base[i] + reach;
    }
    lo_[2] = base[2] + kAboveFloor;  // the floor the robot stands on is no obstacle to it
  }
  // Throws RpcError (naming the map) when it does not answer.
  void update(motion::CollisionModel& world, int64_t as_of_frame) {
    skillbus_msgs::map_query_t q{};
    q.as_of_frame = as_of_frame;
    for (int i = 0; i < 3; ++i) {
      q.box_min[i] = lo_[i];
      q.box_max[i] = hi_[i];
    }
    CallOptions opts;
    opts.timeout = std::chrono::seconds(20);
    skillbus_msgs::map_reply_t r;
    try {
      r = rpc_.call<skillbus_msgs::map_reply_t>("occupied", q, opts);
    } catch (const RpcError& e) {
      throw RpcError(std::string("the occupancy map did not answer (motion_server --map): ") + e.what());
    }
    std::vector<Eigen::Vector3d> voxels;
    voxels.reserve(r.voxels.size());
    for (const auto& v : r.voxels) voxels.emplace_back(v[0], v[1], v[2]);
    if (!holding_ || voxels != last_ || r.resolution != resolution_) {  // rebuilding the grid costs; the map seldom changes
      world.set_map(voxels, r.resolution);
      last_ = std::move(voxels);
      resolution_ = r.resolution;
      holding_ = true;
    }
  }

  // The collision model without the map (a straight line's check): the next update puts
  // it back. (What the cache remembers is what the model holds: a line cleared the model
  // while the cache still held the map, and the next joint-space move, seeing the map
  // unchanged, was planned against fixtures alone, through what the map held.)
  void take_out(motion::CollisionModel& world) {
    world.set_map({}, 0);
    holding_ = false;
  }

 private:
  static constexpr double kAboveFloor = 0.02;  // m
  std::unique_ptr<Bus> bus_;
  RpcClient rpc_;
  double lo_[3], hi_[3];
  std::vector<Eigen::Vector3d> last_;
  double resolution_ = 0;
  bool holding_ = false;  // the collision model holds last_ (a line takes it out)
};

constexpr double kMinSpeedScale = 0.01;  // of the joints' velocity limits: 1 % (slower is no plan's)

skillbus_msgs::motion_plan_t handle(const motion::Kinematics& k, motion::CollisionModel& world, MapSource* map,
                                    const skillbus_msgs::motion_request_t& req) {
  skillbus_msgs::motion_plan_t out{};
  const auto& joints = k.joints();
  if (req.joint_names.size() != joints.size() || req.start.size() != joints.size())
    throw RpcBadRequest("plan: give all " + std::to_string(joints.size()) + " arm joints, in order");
  for (size_t i = 0; i < joints.size(); ++i) {
    if (req.joint_names[i] != joints[i].name)
      throw RpcBadRequest("plan: joint " + std::to_string(i) + " is '" + req.joint_names[i] + "', expected '" +
                          joints[i].name + "'");
    if (!std::isfinite(req.start[i])) throw RpcBadRequest("plan: start of " + joints[i].name + " is not finite");
    // Finite is not enough: a joint at 1e300 rad makes the kinematics' transforms invalid
    // (DART aborts). An arm's start lies within its limits, give or take a little.
    const double slack = 0.1;  // rad: a measured position may overshoot a limit slightly
    if (req.start[i] < joints[i].lower - slack || req.start[i] > joints[i].upper + slack)
      throw RpcBadRequest("plan: start of " + joints[i].name + " (" + std::to_string(req.start[i]) +
                          " rad) is outside its limits [" + std::to_string(joints[i].lower) + ", " +
                          std::to_string(joints[i].upper) + "]");
  }
  for (double v : req.target)
    if (!std::isfinite(v)) throw RpcBadRequest("plan: the target pose is not finite");
  for (int i = 0; i < 3; ++i)
    if (std::abs(req.target[i]) > 1e3) throw RpcBadRequest("plan: the target position is beyond 1 km");
  const Eigen::Quaterniond q(req.target[6], req.target[3], req.target[4], req.target[5]);
  if (std::abs(q.norm() - 1.0) > 1e-3) throw RpcBadRequest("plan: the target quaternion is not a unit quaternion");
  for (double v : req.held)
    if (!std::isfinite(v) || v < 0 || v > 2) throw RpcBadRequest("plan: a held object's sides must be within [0, 2] m");
  // 0 or less: the defaults (motion_request_t). A tiny positive speed_scale made a segment's
  // time overflow into a short one: the fastest move, answered ok; one over 1 was taken
  // as 1 without a word.
  if (!std::isfinite(req.speed_scale) || (req.speed_scale > 0 && (req.speed_scale < kMinSpeedScale || req.speed_scale > 1)))
    throw RpcBadRequest("plan: speed_scale " + std::to_string(req.speed_scale) + " must be within [" +
                        std::to_string(kMinSpeedScale) + ", 1] (0: the default, 0.5)");
  if (!std::isfinite(req.step_m) || req.step_m > 1.0)
    throw RpcBadRequest("plan: step_m " + std::to_string(req.step_m) + " must be at most 1 m (0: the default, 0.01)");
  motion::PlanRequest pr;
  pr.start = Eigen::Map<const Eigen::VectorXd>(req.start.data(), static_cast<Eigen::Index>(req.start.size()));
  pr.target.translation() = Eigen::Vector3d(req.target[0], req.target[1], req.target[2]);
  pr.target.linear() = q.normalized().toRotationMatrix();
  pr.cartesian = req.cartesian;
  pr.step_m = req.step_m;
  pr.speed_scale = req.speed_scale;
  pr.held = Eigen::Vector3d(req.held[0], req.held[1], req.held[2]);
  // The map for joint-space moves only: a straight line is how a skill goes the last
  // centimetres to what it grasps or where it places, which the map holds as occupied.
  if (map && !req.cartesian) map->update(world, req.as_of_frame);
  if (map && req.cartesian) map->take_out(world);
  const motion::Plan p = motion::plan_motion(k, pr, &world);
  out.ok = p.ok;
  out.error = p.error;
  out.position_error = p.position_error;
  out.orientation_error = p.orientation_error;
  out.seeds_tried = p.seeds_tried;
  out.how = p.how;
  out.iterations = p.iterations;
  for (const auto& j : joints) out.joint_names.push_back(j.name);
  out.num_joints = static_cast<int32_t>(joints.size());
  if (p.ok) out.goal.assign(p.goal.data(), p.goal.data() + p.goal.size());
  else out.goal.assign(joints.size(), 0.0);
  for (const auto& [t, qs] : p.points) {
    skillbus_msgs::joint_traj_point_t pt{};
    pt.time_from_start_ns = t;
    pt.positions.assign(qs.data(), qs.data() + qs.size());
    pt.num_positions = static_cast<int32_t>(pt.positions.size());
    if (p.rests_at_points) pt.velocities.assign(qs.size(), 0.0);  // straight joint segments between the points
    pt.num_velocities = static_cast<int32_t>(pt.velocities.size());
    out.points.push_back(pt);
  }
  out.num_points = static_cast<int32_t>(out.points.size());
  return out;
}
}  // namespace

constexpr double kReach = 1.2;  // m around the robot's base: the map the arm can run into

int main(int argc, char** argv) {
  CLI::App app{"Arm motion for the skills over RPC (area MOTION, method plan): inverse kinematics (Ceres) and "
               "joint trajectories for the scene's arm. SIGTERM or SIGINT stop it; it prints a one-line JSON summary.",
               "motion_server"};
  apps::configure(app);
  std::string url, scene_file;
  apps::add_url_option(app, url);
  app.add_option("--scene", scene_file, "the scene file the robot comes from (required)")->type_name("FILE");
  apps::add_robot_option(app);  // which of the scene's robots, and its MOTION channels
  bool use_map = false;
  app.add_flag("--map", use_map,
               "check joint-space moves against the occupancy map too (map_server, RPC area MAP), as of the "
               "asker's frame");
  apps::parse_or_exit(app, argc, argv);
  if (scene_file.empty()) apps::usage_error(app, "--scene FILE is required (the robot comes from it)");
  std::unique_ptr<Bus> bus;
  std::unique_ptr<motion::Kinematics> kin;
  std::unique_ptr<motion::CollisionModel> world;
  std::unique_ptr<MapSource> map;
  apps::start_or_exit("motion_server", [&] {
    const scene::Scene scene = scene::load_scene(scene_file);
    kin = std::make_unique<motion::Kinematics>(scene, current_robot());
    world = std::make_unique<motion::CollisionModel>(scene, current_robot());
    bus = open_bus(url);
    if (use_map) map = std::make_unique<MapSource>(open_bus(url), *kin, kReach);
  });
  RpcServer rpc(*bus, "MOTION");
  rpc.add_method<skillbus_msgs::motion_request_t, skillbus_msgs::motion_plan_t>(
      "plan", [&](const skillbus_msgs::motion_request_t& r) { return handle(*kin, *world, map.get(), r); });
  apps::stop_on_signals();
  SB_INFO("motion_server", "serving " << rpc_request_channel("MOTION") << " for " << kin->joints().size()
                                      << " arm joints of " << scene_file);
  while (!apps::stop_requested()) bus->handle(std::chrono::milliseconds(100));
  apps::Summary out;
  out["ok"] = true;
  out["served"] = rpc.served();
  out["bad_input"] = rpc.bad_input().total();
  // Messages the bus refused (no key, a wrong key, replayed, stale, not this sender's channel).
  if (const auto* a = auth::stats_of(*bus)) out["bus_rejected"] = a->rejected;
  apps::print_summary(out);
  return 0;
}
