// The physics server process: the robot's interface over LCM as a real robot's drivers
// speak it (arm trajectories in; arm state, camera detections and replies out every
// frame), the simulated fingers' channel (finger commands in, from the simulated gripper
// device), the simulator's ground truth every frame, the control services over RPC (area
// SIM), and the clock: lockstep master with the participants named at launch, or paced
// to the wall clock.
//
// Reads:   SB_ROBOT_ARM_CMD (robot_arm_cmd_t), SB_SIM_GRIPPER_CMD (sim_gripper_cmd_t),
//          SB_SIM_ATTACH (sim_attach_t), SB_SIM_REQ, SB_CAMERA_CAPTURE (camera_capture_t)
// Writes:  SB_ROBOT_ARM_STATE (robot_arm_state_t), SB_ROBOT_OBJECTS (robot_objects_t),
//          SB_ROBOT_ARTICULATION (articulation_state_t; only for a scene with articulated objects),
//          SB_ROBOT_CMD_REPLY (robot_cmd_reply_t, arm commands), SB_SIM_STATE (sim_state_t),
//          SB_SIM_CMD_REPLY (sim_cmd_reply_t, finger and attach commands), SB_SIM_REP,
//          SB_CAMERA_CLOUD (camera_cloud_t: the depth cameras' clouds, on request and at their rate),
//          SB_LOCKSTEP_CLOCK (as master)
// With several robots in the scene, each robot's channels (all but SB_SIM_REQ/REP and the
// lockstep's) are under its name: r2/SB_ROBOT_ARM_CMD (skillbus/bus.hpp, robot_channel()).
#pragma once

#include <chrono>
#include <map>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "skillbus/bus.hpp"
#include "skillbus/lockstep.hpp"
#include "skillbus/rpc.hpp"
#include "skillbus/sim/physics.hpp"
#include "skillbus/sim/script.hpp"
#include "skillbus_msgs/sim_status_t.hpp"

namespace skillbus::sim {

// A robot's channels (any robot: this server, or a real robot's drivers), for the robot
// with that bus name ("": the one robot of a one-robot scene).
std::string robot_arm_state_channel(const std::string& robot = "");  // SB_ROBOT_ARM_STATE
std::string robot_arm_cmd_channel(const std::string& robot = "");    // SB_ROBOT_ARM_CMD
std::string robot_reply_channel(const std::string& robot = "");      // SB_ROBOT_CMD_REPLY
std::string robot_objects_channel(const std::string& robot = "");    // SB_ROBOT_OBJECTS
std::string robot_articulation_channel(const std::string& robot = "");  // SB_ROBOT_ARTICULATION
// The simulator's own: its ground truth and the simulated fingers, per robot.
std::string state_channel(const std::string& robot = "");    // SB_SIM_STATE
std::string gripper_channel(const std::string& robot = "");  // SB_SIM_GRIPPER_CMD
std::string reply_channel(const std::string& robot = "");    // SB_SIM_CMD_REPLY
std::string attach_channel(const std::string& robot = "");   // SB_SIM_ATTACH

struct ServerOptions {
  std::string scene_file;
  std::string scenes_dir;                  // SIM.load_scene's names (default: scene_file's folder)
  std::string script_file;                 // commands played in-process (no participant needed)
  std::string record_script;               // write every accepted command here, as a script
  std::string name = "sim";
  std::vector<std::string> participants;  // lockstep: who must join and ack every frame
  // Lockstep: a session asked to end by a participant ends when each of these has asked
  // (at the latest frame asked for); empty: when the first asks.
  std::vector<std::string> end_when_asked_by;
  bool wall_clock = false;
  double speed = 1.0;                      // wall-clock mode: sim seconds per wall second
  int64_t frames = -1;                     // -1: until stopped
  double duration_s = 0;                   // > 0: run this much sim time (overrides frames)
  // Lockstep: step the physics while the participants work (the commands of frame n
  // are applied in frame n + 1, one frame later than without it).
  bool pipeline = false;
  std::string collision_detector;          // overrides the scene's when set
  double step_ms = 0, frame_ms = 0;        // override the scene's when > 0
  std::chrono::milliseconds join_timeout{10000}, ack_timeout{5000}, message_timeout{2000};
  std::map<std::string, std::chrono::milliseconds> ack_timeout_of;  // participants allowed longer frames
  // Lockstep: poll for the acks this long after the step before sleeping (MasterConfig::ack_poll;
  // for a server on a core of its own).
  std::chrono::microseconds ack_poll{0};
};

struct ServerReport {
  RunResult run;
  int64_t steps = 0;
  double physics_seconds = 0;
  Digest state_digest{};
  long accepted = 0, rejected = 0, bad_input = 0;
  // Where the wall time went (seconds, summed over the run): for benchmarks.
  double frame_start_seconds = 0, frame_end_seconds = 0, ack_wait_seconds = 0;
  std::map<std::string, double> ack_seconds;
  std::map<std::string, double> held_seconds;  // each participant's ack past the physics' step
  std::map<std::string, int64_t> ended_by;     // frames whose last ack was each participant's
};

class SimServer {
 public:
  SimServer(Bus& bus, ServerOptions options);  // throws scene::SceneError on a bad scene
  ~SimServer();
  ServerReport run_until(std::function<bool()> should_stop);
  const Physics& physics() const { return *physics_; }

 private:
  scene::Scene load(const std::string& path) const;  // the file, with the command-line overrides
  void on_arm(size_t robot, const uint8_t* data, size_t size, const std::string& ch);
  void on_gripper(size_t robot, const uint8_t* data, size_t size, const std::string& ch);
  void on_attach(size_t robot, const uint8_t* data, size_t size, const std::string& ch);
  void on_capture(const uint8_t* data, size_t size, const std::string& ch);
  template <class Publish>
  void publish_captures(Publish&& publish);
  void on_command(const std::string& ch, const uint8_t* data, size_t size);  // by the channel's robot and kind
  void reply(size_t robot, const std::string& id, const std::string& command, const std::string& error);
  std::vector<std::string> command_channels() const;  // every robot's arm, finger and attach command channels
  size_t robot_of_script_step(const ScriptStep& s) const;
  std::string unplayed_steps() const;  // "" or how many --script steps the run left out
  template <class Publish>
  void publish_frame(Publish&& publish);
  ServerReport run_lockstep(const std::function<bool()>& should_stop);
  ServerReport run_wall_clock(const std::function<bool()>& should_stop);
  void add_services();
  void play_script();  // the in-process script's steps due by the current sim time
  skillbus_msgs::sim_status_t status() const;
  ServerReport report(const RunResult& r) const;

  Bus& bus_;
  ServerOptions opt_;
  std::unique_ptr<Physics> physics_;
  std::string scenes_dir_;  // where SIM.load_scene finds a scene by name
  std::unique_ptr<RpcServer> rpc_;
  BadInputCounter bad_{"sim_server"};
  struct Reply {
    size_t robot = 0;
    std::string id, command, error;  // command: "arm" (SB_ROBOT_CMD_REPLY), "gripper" or "attach" (SB_SIM_CMD_REPLY)
  };
  std::vector<Reply> pending_replies_;  // published at the next frame's start, in this order
  struct CaptureRequest {
    size_t camera_index = 0;
    std::string id, camera, error;  // error: the request is refused with it
  };
  std::vector<CaptureRequest> pending_captures_;  // captured at the next frame's start
  std::vector<int64_t> captures_;                 // per camera: captures so far
  std::vector<int64_t> last_rate_capture_;        // per camera: the sim frame of its last rate capture
  long accepted_ = 0, rejected_ = 0;
  int64_t frame_ = -1, sim_time_ns_ = 0;
  bool paused_ = false;
  std::vector<ScriptStep> script_;
  // Pipelined lockstep: commands of this frame, applied at the next frame's step.
  std::vector<std::pair<std::string, Bytes>> pending_commands_;
  void apply_pending();
  std::vector<std::string> recorded_;  // script steps (JSON) of the accepted commands
  void record(size_t robot, const ArmCommand* arm, const GripperCommand* gripper, const AttachCommand* attach = nullptr);
  // Writes --record-script ("" when done, else why not). The file is written once the
  // run ends, in either mode; made at start, so that a path it cannot be written to is
  // refused then rather than found out after the run.
  std::string write_recording() const;
  size_t script_next_ = 0;
};

}  // namespace skillbus::sim
