#include "skillbus/sim/server.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "skillbus/lockstep_frame.hpp"
#include "skillbus/log.hpp"
#include "skillbus_msgs/articulation_state_t.hpp"
#include "skillbus_msgs/robot_arm_cmd_t.hpp"
#include "skillbus_msgs/robot_arm_state_t.hpp"
#include "skillbus_msgs/robot_cmd_reply_t.hpp"
#include "skillbus_msgs/robot_objects_t.hpp"
#include "skillbus_msgs/camera_capture_t.hpp"
#include "skillbus_msgs/camera_cloud_t.hpp"
#include "skillbus/files.hpp"
#include "skillbus_msgs/sim_attach_t.hpp"
#include "skillbus_msgs/sim_cmd_reply_t.hpp"
#include "skillbus_msgs/sim_control_t.hpp"
#include "skillbus_msgs/sim_gripper_cmd_t.hpp"
#include "skillbus_msgs/sim_status_t.hpp"

namespace skillbus::sim {

using scene::Scene;
using scene::SceneError;

namespace {
constexpr const char* kLog = "sim_server";
}

std::string robot_arm_state_channel(const std::string& robot) { return robot_channel("SB_ROBOT_ARM_STATE", robot); }
std::string robot_arm_cmd_channel(const std::string& robot) { return robot_channel("SB_ROBOT_ARM_CMD", robot); }
std::string robot_reply_channel(const std::string& robot) { return robot_channel("SB_ROBOT_CMD_REPLY", robot); }
std::string robot_objects_channel(const std::string& robot) { return robot_channel("SB_ROBOT_OBJECTS", robot); }
std::string robot_articulation_channel(const std::string& robot) { return robot_channel("SB_ROBOT_ARTICULATION", robot); }
std::string state_channel(const std::string& robot) { return robot_channel("SB_SIM_STATE", robot); }
std::string gripper_channel(const std::string& robot) { return robot_channel("SB_SIM_GRIPPER_CMD", robot); }
std::string reply_channel(const std::string& robot) { return robot_channel("SB_SIM_CMD_REPLY", robot); }
std::string attach_channel(const std::string& robot) { return robot_channel("SB_SIM_ATTACH", robot); }
std::string camera_capture_channel() { return channel("SB_CAMERA_CAPTURE"); }
std::string camera_cloud_channel() { return channel("SB_CAMERA_CLOUD"); }

SimServer::SimServer(Bus& bus, ServerOptions options) : bus_(bus), opt_(std::move(options)) {
  if (!(opt_.speed > 0) || !std::isfinite(opt_.speed)) throw SceneError("--speed must be a positive number");
  for (const auto& name : opt_.end_when_asked_by)  // (the master checks it too; here it fails at start)
    if (std::find(opt_.participants.begin(), opt_.participants.end(), name) == opt_.participants.end())
      throw SceneError("--end-when-asked-by names '" + name + "', who is not among --participants");
  for (const auto& [name, ms] : opt_.ack_timeout_of)
    if (std::find(opt_.participants.begin(), opt_.participants.end(), name) == opt_.participants.end())
      throw SceneError("--ack-timeout-ms-of names '" + name + "', who is not among --participants");
  physics_ = std::make_unique<Physics>(load(opt_.scene_file));
  scenes_dir_ = opt_.scenes_dir;
  if (scenes_dir_.empty()) {
    const auto slash = opt_.scene_file.rfind('/');
    scenes_dir_ = slash == std::string::npos ? "." : opt_.scene_file.substr(0, slash);
  }
  if (opt_.duration_s > 0)
    opt_.frames = static_cast<int64_t>(std::llround(opt_.duration_s / (physics_->scene().physics.frame_ms * 1e-3)));
  if (!opt_.script_file.empty()) script_ = load_script(opt_.script_file);
  if (const std::string why = write_recording(); !why.empty()) throw SceneError(why);  // (empty for now)
  rpc_ = std::make_unique<RpcServer>(bus_, "SIM");
  add_services();
}

SimServer::~SimServer() = default;

Scene SimServer::load(const std::string& path) const {
  Scene s = scene::load_scene(path);
  if (!opt_.collision_detector.empty()) {
    if (opt_.collision_detector != "bullet" && opt_.collision_detector != "dart" && opt_.collision_detector != "fcl")
      throw SceneError("--collision must be one of bullet, dart, fcl (got '" + opt_.collision_detector + "')");
    s.physics.collision_detector = opt_.collision_detector;
  }
  if (opt_.step_ms > 0) s.physics.step_ms = opt_.step_ms;
  if (opt_.frame_ms > 0) s.physics.frame_ms = opt_.frame_ms;
  const double ratio = s.physics.frame_ms / s.physics.step_ms;
  if (s.physics.frame_ms < s.physics.step_ms || std::abs(ratio - std::round(ratio)) > 1e-9)
    throw SceneError("the frame (" + std::to_string(s.physics.frame_ms) + " ms) must be a whole number of steps (" +
                     std::to_string(s.physics.step_ms) + " ms)");
  return s;
}

void SimServer::reply(size_t robot, const std::string& id, const std::string& command, const std::string& error) {
  if (error.empty()) {
    ++accepted_;
  } else {
    ++rejected_;
    const std::string& bus_name = physics_->scene().robots[robot].bus_name;  // (several robots: which one)
    SB_WARN(kLog, "rejected " << command << " command '" << id << "'" << (bus_name.empty() ? "" : " of robot " + bus_name)
                              << ": " << error);
  }
  pending_replies_.push_back({robot, id, command, error});
}

std::vector<std::string> SimServer::command_channels() const {
  std::vector<std::string> out;
  for (const auto& r : physics_->scene().robots) {
    out.push_back(robot_arm_cmd_channel(r.bus_name));
    out.push_back(gripper_channel(r.bus_name));
    out.push_back(attach_channel(r.bus_name));
  }
  out.push_back(camera_capture_channel());
  return out;
}

// A command goes to the robot whose channel it came on.
void SimServer::on_command(const std::string& ch, const uint8_t* data, size_t size) {
  const auto& robots = physics_->scene().robots;
  for (size_t i = 0; i < robots.size(); ++i) {
    if (ch == robot_arm_cmd_channel(robots[i].bus_name)) return on_arm(i, data, size, ch);
    if (ch == gripper_channel(robots[i].bus_name)) return on_gripper(i, data, size, ch);
    if (ch == attach_channel(robots[i].bus_name)) return on_attach(i, data, size, ch);
  }
  if (ch == camera_capture_channel()) return on_capture(data, size, ch);
  bad_.record(ch, "a command on a channel of no robot of the scene", size);
}

// A capture request is answered at the next frame's start: its cloud, or the reason why not.
void SimServer::on_capture(const uint8_t* data, size_t size, const std::string& ch) {
  skillbus_msgs::camera_capture_t m;
  if (!decode_msg(data, size, m)) {
    bad_.record(ch, "does not decode as camera_capture_t", size);
    return;
  }
  const auto& cams = physics_->scene().cameras;
  for (size_t i = 0; i < cams.size(); ++i)
    if (cams[i].name == m.camera) {
      pending_captures_.push_back({i, m.id, m.camera, ""});
      return;
    }
  std::string known;
  for (const auto& c : cams) known += (known.empty() ? "" : ", ") + c.name;
  const std::string error = "no camera '" + m.camera + "' in the scene (cameras: " + (known.empty() ? "none" : known) + ")";
  SB_WARN(kLog, "capture request '" << m.id << "': " << error);
  pending_captures_.push_back({cams.size(), m.id, m.camera, error});
}

// This frame's captures: the requests since the last frame (in the order the frame
// delivered them), then every camera whose rate makes one due at this sim time.
template <class Publish>
void SimServer::publish_captures(Publish&& publish) {
  const auto& cams = physics_->scene().cameras;
  captures_.resize(cams.size(), 0);
  last_rate_capture_.resize(cams.size(), -1);
  auto capture = [&](size_t i, const std::string& request_id) {
    const DepthCapture c = physics_->capture(i, captures_[i]);
    for (auto& part : cloud_parts(c, request_id, captures_[i])) publish(camera_cloud_channel(), part);
    ++captures_[i];
  };
  for (const auto& p : pending_captures_) {
    if (!p.error.empty()) {
      publish(camera_cloud_channel(), cloud_error(p.camera, p.id, p.error));
      continue;
    }
    capture(p.camera_index, p.id);
  }
  pending_captures_.clear();
  const double frame_s = physics_->scene().physics.frame_ms * 1e-3;
  const int64_t frame_ns = static_cast<int64_t>(std::llround(frame_s * 1e9));
  const int64_t sim_frame = frame_ns > 0 ? sim_time_ns_ / frame_ns : 0;  // (frames of sim time: a paused frame repeats it)
  for (size_t i = 0; i < cams.size(); ++i) {
    if (!(cams[i].rate_hz > 0)) continue;
    const int64_t every = std::max<int64_t>(1, std::llround(1.0 / (cams[i].rate_hz * frame_s)));
    if (sim_frame % every != 0 || sim_frame == last_rate_capture_[i]) continue;
    last_rate_capture_[i] = sim_frame;
    capture(i, "");
  }
}

size_t SimServer::robot_of_script_step(const ScriptStep& s) const {
  const auto& robots = physics_->scene().robots;
  for (size_t i = 0; i < robots.size(); ++i)
    if (robots[i].bus_name == s.robot) return i;
  return robots.size();  // (none: the step is rejected)
}

void SimServer::on_arm(size_t robot, const uint8_t* data, size_t size, const std::string& ch) {
  skillbus_msgs::robot_arm_cmd_t m;
  if (!decode_msg(data, size, m)) {
    bad_.record(ch, "does not decode as robot_arm_cmd_t", size);
    ++rejected_;
    return;
  }
  ArmCommand c;
  c.id = m.id;
  c.joints = m.joint_names;
  for (const auto& p : m.points) {
    Waypoint w;
    w.t_ns = p.time_from_start_ns;
    w.q = p.positions;
    w.qd = p.velocities;
    c.points.push_back(std::move(w));
  }
  const std::string err = physics_->command_arm(robot, c);
  if (err.empty()) record(robot, &c, nullptr);
  reply(robot, m.id, "arm", err);
}

void SimServer::record(size_t robot, const ArmCommand* arm, const GripperCommand* gripper, const AttachCommand* attach) {
  if (opt_.record_script.empty()) return;
  nlohmann::json step;
  step["at_s"] = static_cast<double>(sim_time_ns_) * 1e-9;
  const std::string& bus_name = physics_->scene().robots[robot].bus_name;
  if (!bus_name.empty()) step["robot"] = bus_name;
  if (arm) {
    nlohmann::json pts = nlohmann::json::array();
    // [t, q], or [t, q, qd] when the command gave velocities (the follower derives them
    // otherwise): a replay must follow the same trajectory.
    for (const auto& w : arm->points) {
      nlohmann::json pt = {static_cast<double>(w.t_ns) * 1e-9, w.q};
      if (!w.qd.empty()) pt.push_back(w.qd);
      pts.push_back(std::move(pt));
    }
    step["arm"] = {{"id", arm->id}, {"joints", arm->joints}, {"points", pts}};
  } else if (attach) {
    step["attach"] = {{"id", attach->id}, {"attach", attach->attach}, {"object", attach->object}};
  } else {
    step["gripper"] = {{"id", gripper->id}, {"width", gripper->width}, {"speed", gripper->speed},
                       {"force_limit", gripper->force_limit}};
  }
  recorded_.push_back(step.dump());
}

std::string SimServer::write_recording() const {
  if (opt_.record_script.empty()) return "";
  errno = 0;
  std::ofstream out(opt_.record_script);
  if (out) {
    out << "{\"record_every\": 10, \"steps\": [\n";
    for (size_t i = 0; i < recorded_.size(); ++i)
      out << "  " << recorded_[i] << (i + 1 < recorded_.size() ? ",\n" : "\n");
    out << "]}\n";
    out.close();
  }
  if (out) return "";
  const int e = errno;
  return "cannot write the recorded script to " + opt_.record_script + (e ? std::string(": ") + std::strerror(e) : "");
}

// A run's result with what the caller asked for beside it: a run whose commands could not
// be written where --record-script asked, or that ended before its --script's last step,
// is not ok.
static RunResult with_failure(RunResult r, const std::string& failed) {
  if (failed.empty()) return r;
  SB_ERROR("sim_server", failed);
  if (r.ok) {
    r.ok = false;
    r.error = failed;
  }
  return r;
}

void SimServer::on_gripper(size_t robot, const uint8_t* data, size_t size, const std::string& ch) {
  skillbus_msgs::sim_gripper_cmd_t m;
  if (!decode_msg(data, size, m)) {
    bad_.record(ch, "does not decode as sim_gripper_cmd_t", size);
    ++rejected_;
    return;
  }
  GripperCommand c{m.id, m.width, m.speed, m.force_limit};
  const std::string err = physics_->command_gripper(robot, c);
  if (err.empty()) record(robot, nullptr, &c);
  reply(robot, m.id, "gripper", err);
}

// Attach and detach: taken like a finger command (applied where the frame delivers it,
// answered on the simulator's reply channel).
void SimServer::on_attach(size_t robot, const uint8_t* data, size_t size, const std::string& ch) {
  skillbus_msgs::sim_attach_t m;
  if (!decode_msg(data, size, m)) {
    bad_.record(ch, "does not decode as sim_attach_t", size);
    ++rejected_;
    return;
  }
  AttachCommand c{m.id, m.attach != 0, m.object};
  const std::string err = physics_->attach(robot, c.object, c.attach);
  if (err.empty()) record(robot, nullptr, nullptr, &c);
  reply(robot, m.id, "attach", err);
}

void SimServer::apply_pending() {
  const auto cmds = std::move(pending_commands_);
  pending_commands_.clear();
  for (const auto& [ch, data] : cmds) on_command(ch, data.data(), data.size());
}

std::string SimServer::unplayed_steps() const {
  if (script_next_ >= script_.size()) return "";
  std::ostringstream why;
  why << (script_.size() - script_next_) << " step(s) of " << opt_.script_file
      << " not played: the session ended at sim time " << sim_time_ns_ * 1e-9 << " s, before the step at "
      << script_[script_next_].at_ns * 1e-9 << " s";
  return why.str();
}

void SimServer::play_script() {
  while (script_next_ < script_.size() && script_[script_next_].at_ns <= sim_time_ns_) {
    const ScriptStep& s = script_[script_next_++];
    const size_t robot = robot_of_script_step(s);
    if (robot == physics_->num_robots()) {
      ++rejected_;
      SB_WARN(kLog, "script step at " << s.at_ns * 1e-9 << " s: the scene has no robot '" << s.robot << "'");
    } else if (s.is_arm) {
      reply(robot, s.arm.id, "arm", physics_->command_arm(robot, s.arm));
    } else if (s.is_attach) {
      reply(robot, s.attach.id, "attach", physics_->attach(robot, s.attach.object, s.attach.attach));
    } else {
      reply(robot, s.gripper.id, "gripper", physics_->command_gripper(robot, s.gripper));
    }
  }
}

// Every frame, for each robot in scene order: the replies to its commands applied since
// the last frame (arm commands are the robot's, finger and attach commands the
// simulator's), its arm state and camera, the articulated objects' joints (only for a
// scene that has any: other scenes publish exactly what they did before), and the
// simulator's ground truth around it.
template <class Publish>
void SimServer::publish_frame(Publish&& publish) {
  const auto& robots = physics_->scene().robots;
  skillbus_msgs::robot_objects_t objects{};
  physics_->fill_objects(objects);  // (one camera view of the world, sent to each robot)
  for (size_t i = 0; i < robots.size(); ++i) {
    const std::string& robot = robots[i].bus_name;
    for (const auto& p : pending_replies_) {
      if (p.robot != i) continue;
      if (p.command == "arm") {
        skillbus_msgs::robot_cmd_reply_t r{};
        r.id = p.id;
        r.command = p.command;
        r.accepted = p.error.empty();
        r.error = p.error;
        publish(robot_reply_channel(robot), r);
      } else {
        skillbus_msgs::sim_cmd_reply_t r{};
        r.id = p.id;
        r.accepted = p.error.empty();
        r.error = p.error;
        publish(reply_channel(robot), r);
      }
    }
    skillbus_msgs::robot_arm_state_t arm{};
    physics_->fill_arm_state(i, arm);
    publish(robot_arm_state_channel(robot), arm);
    publish(robot_objects_channel(robot), objects);
    if (!physics_->scene().articulated.empty()) {
      skillbus_msgs::articulation_state_t joints{};
      physics_->fill_articulation(i, joints);
      publish(robot_articulation_channel(robot), joints);
    }
    skillbus_msgs::sim_state_t s{};
    physics_->fill_state(i, s);
    publish(state_channel(robot), s);
  }
  pending_replies_.clear();
  publish_captures(publish);
}

skillbus_msgs::sim_status_t SimServer::status() const {
  skillbus_msgs::sim_status_t s{};
  s.frame = frame_;
  s.sim_time_ns = sim_time_ns_;
  s.lockstep = !opt_.wall_clock;
  s.paused = paused_;
  s.scene = physics_->scene().path;
  s.digest = to_hex(physics_->digest());
  s.collision_detector = physics_->collision_detector();
  s.num_objects = static_cast<int32_t>(physics_->scene().objects.size());
  s.commands_accepted = accepted_;
  s.commands_rejected = rejected_;
  return s;
}

void SimServer::add_services() {
  using Req = skillbus_msgs::sim_control_t;
  using Rep = skillbus_msgs::sim_status_t;
  rpc_->add_method<Req, Rep>("status", [this](const Req&) { return status(); });
  rpc_->add_method<Req, Rep>("digest", [this](const Req&) { return status(); });
  rpc_->add_method<Req, Rep>("reset", [this](const Req&) {
    physics_->reset();
    // As a scene loaded anew: the cameras count from 0 again, and so seed their noise (a
    // capture after a reset differed from the same capture of a fresh start).
    captures_.clear();
    last_rate_capture_.clear();
    pending_captures_.clear();
    SB_INFO(kLog, "reset to the scene " << physics_->scene().path << " at frame " << frame_);
    return status();
  });
  rpc_->add_method<Req, Rep>("load_scene", [this](const Req& r) {
    if (r.scene.empty()) throw RpcBadRequest("load_scene needs a scene name");
    // A scene by name, from the folder of the scene the server started with (or
    // --scenes): a request never names a path (skillbus/files.hpp).
    std::string path;
    try {
      path = file_in(scenes_dir_, r.scene, ".scene.json", "scene name");
    } catch (const std::invalid_argument& e) {
      throw RpcBadRequest(e.what());
    }
    Scene s = load(path);  // a SceneError becomes the error reply; the old world stays
    // The frame period is fixed at start in either mode (the lockstep clock's, the wall-clock
    // loop's): on the wall clock a scene of another frame was taken, and its sim time then
    // ran at the old period's pace while the physics stepped the new one.
    if (std::abs(s.physics.frame_ms - physics_->scene().physics.frame_ms) > 1e-9)
      throw RpcError("the scene's frame (" + std::to_string(s.physics.frame_ms) + " ms) differs from the running one (" +
                     std::to_string(physics_->scene().physics.frame_ms) + " ms), fixed at start: start the server "
                     "with that scene instead");
    // The robots' channels are subscribed for the session: a scene with other robots
    // would leave commands unheard.
    std::vector<std::string> now, then;
    for (const auto& r : physics_->scene().robots) now.push_back(r.bus_name);
    for (const auto& r : s.robots) then.push_back(r.bus_name);
    if (now != then) throw RpcError("the scene's robots differ from the running scene's (their channels are fixed)");
    physics_ = std::make_unique<Physics>(s);
    captures_.clear();  // (the new scene's cameras count from 0)
    last_rate_capture_.clear();
    pending_captures_.clear();
    SB_INFO(kLog, "loaded the scene " << s.path << " at frame " << frame_);
    return status();
  });
  auto pause = [this](bool p) {
    if (!opt_.wall_clock)
      throw RpcError("pause and resume are for wall-clock mode; under lockstep the participants set the pace");
    paused_ = p;
    return status();
  };
  rpc_->add_method<Req, Rep>("pause", [pause](const Req&) { return pause(true); });
  rpc_->add_method<Req, Rep>("resume", [pause](const Req&) { return pause(false); });
}

ServerReport SimServer::report(const RunResult& r) const {
  ServerReport rep;
  rep.run = r;
  rep.steps = physics_->step_count();
  rep.physics_seconds = physics_->physics_seconds();
  rep.state_digest = physics_->digest();
  rep.accepted = accepted_;
  rep.rejected = rejected_;
  rep.bad_input = bad_.total();
  return rep;
}

ServerReport SimServer::run_until(std::function<bool()> should_stop) {
  SB_INFO(kLog, "scene " << physics_->scene().path << ": " << physics_->scene().objects.size() << " objects, "
                         << physics_->steps_per_frame() << " steps of " << physics_->scene().physics.step_ms
                         << " ms per frame, collision detector " << physics_->collision_detector() << ", "
                         << (opt_.wall_clock ? "wall-clock mode" : "lockstep master"));
  return opt_.wall_clock ? run_wall_clock(should_stop) : run_lockstep(should_stop);
}

ServerReport SimServer::run_lockstep(const std::function<bool()>& should_stop) {
  MasterConfig cfg;
  cfg.name = opt_.name;
  cfg.participants = opt_.participants;
  cfg.frame_period_ns = static_cast<int64_t>(std::llround(physics_->scene().physics.frame_ms * 1e6));
  cfg.frames = opt_.frames;
  cfg.join_timeout = opt_.join_timeout;
  cfg.ack_timeout = opt_.ack_timeout;
  cfg.ack_timeout_of = opt_.ack_timeout_of;
  cfg.message_timeout = opt_.message_timeout;
  cfg.ack_poll = opt_.ack_poll;
  cfg.end_when_asked_by = opt_.end_when_asked_by;
  LockstepMaster master(bus_, cfg);
  // Commands come through the master: delivered after every ack of their frame, in
  // canonical order, so the order of arrival never reaches the physics.
  if (opt_.pipeline) {
    // Kept in canonical order for the next frame's step (apply_pending).
    auto keep = [this](const StampedMessage& m) { pending_commands_.emplace_back(m.channel, m.data); };
    for (const auto& ch : command_channels()) master.subscribe(ch, keep);
  } else {
    for (const auto& ch : command_channels())
      master.subscribe(ch, [this](const StampedMessage& m) { on_command(m.channel, m.data.data(), m.data.size()); });
  }
  double start_s = 0, end_s = 0;
  using wall = std::chrono::steady_clock;
  master.on_frame_start = [&](int64_t frame, int64_t sim_time) {
    const auto t0 = wall::now();
    frame_ = frame;
    sim_time_ns_ = sim_time;
    publish_frame([&](const std::string& ch, const auto& msg) { master.publish(ch, msg); });
    start_s += std::chrono::duration<double>(wall::now() - t0).count();
  };
  if (opt_.pipeline) {
    master.on_clock_sent = [&](int64_t, int64_t) {
      const auto t0 = wall::now();
      apply_pending();
      play_script();
      physics_->step_frame();
      end_s += std::chrono::duration<double>(wall::now() - t0).count();
    };
  }
  master.on_frame_end = [&](int64_t frame, int64_t) {
    const auto t0 = wall::now();
    if (!opt_.pipeline) {
      play_script();
      physics_->step_frame();
    }
    end_s += std::chrono::duration<double>(wall::now() - t0).count();
  };
  // A stop (SIGTERM, Ctrl-C) ends the session even while the master waits for a join or an
  // ack: the participants are told, and finish cleanly.
  master.interrupted = should_stop;
  RunResult run = master.run();  // (then the recording: an argument's order is unspecified)
  const RunResult r = with_failure(with_failure(std::move(run), write_recording()), unplayed_steps());
  ServerReport rep = report(r);
  rep.bad_input += master.bad_input().total();
  rep.frame_start_seconds = start_s;
  rep.frame_end_seconds = end_s;
  rep.ack_wait_seconds = master.wait_seconds();
  rep.ack_seconds = master.ack_seconds();
  rep.held_seconds = master.held_seconds();
  rep.ended_by = master.ended_by();
  return rep;
}

ServerReport SimServer::run_wall_clock(const std::function<bool()>& should_stop) {
  using clock = std::chrono::steady_clock;
  std::vector<int> subs;
  for (const auto& ch : command_channels())
    subs.push_back(bus_.subscribe(ch, [this](const std::string& c, const uint8_t* d, size_t n) { on_command(c, d, n); }));
  FrameOutbox outbox(bus_, opt_.name);
  const int64_t period_ns = static_cast<int64_t>(std::llround(physics_->scene().physics.frame_ms * 1e6));
  const auto wall_period = std::chrono::nanoseconds(static_cast<int64_t>(period_ns / opt_.speed));
  const auto start = clock::now();
  auto deadline = start;
  RunResult r;
  int64_t frame = 0;  // frames stepped (sim time stands still while paused)
  int64_t tick = 0;   // frames published, paused or not
  while ((opt_.frames < 0 || frame < opt_.frames) && !should_stop()) {
    frame_ = tick++;
    sim_time_ns_ = frame * period_ns;
    outbox.begin_frame(frame_, sim_time_ns_);
    publish_frame([&](const std::string& ch, const auto& msg) { outbox.publish(ch, msg); });
    outbox.finish_frame();
    deadline += wall_period;
    for (auto now = clock::now(); now < deadline; now = clock::now())
      bus_.handle(std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now) + std::chrono::milliseconds(0));
    // Behind by more than a second (a stalled machine): do not try to catch up in a burst.
    if (clock::now() - deadline > std::chrono::seconds(1)) deadline = clock::now();
    if (paused_) continue;
    play_script();
    physics_->step_frame();
    ++frame;
  }
  for (int sub : subs) bus_.unsubscribe(sub);
  r.frames = frame;
  r.sim_time_ns = frame * period_ns;
  r.wall_seconds = std::chrono::duration<double>(clock::now() - start).count();
  r.digest = physics_->digest();
  return report(with_failure(with_failure(r, write_recording()), unplayed_steps()));
}

}  // namespace skillbus::sim
