// The skill manager process (see skill_mgr/README.md for its RPCs and channels).
#pragma once

#include <array>
#include <chrono>
#include <deque>
#include <map>
#include <memory>
#include <string>

#include "registry.hpp"
#include "blackboard.hpp"
#include "directory.hpp"
#include "liveness.hpp"
#include "task_context.hpp"
#include "tree/node.hpp"
#include "world_replica.hpp"
#include "skillbus/lockstep.hpp"
#include "skillbus/rpc.hpp"
#include "skillbus_msgs/skill_progress_list_t.hpp"
#include "skillbus_msgs/skill_progress_t.hpp"
#include "skillbus_msgs/skill_start_t.hpp"
#include "skillbus_msgs/skill_task_t.hpp"

namespace skillbus::skills {

// What one registration may add (anyone with the bus key may register).
constexpr size_t kMaxProcesses = 64;
constexpr size_t kMaxSkillsPerProcess = 1024;

struct ManagerOptions {
  std::string name = "skill_mgr";         // lockstep participant name
  bool wall_clock = false;
  int64_t frame_period_ns = 10'000'000;   // wall-clock mode
  int64_t tick_period_ns = 40'000'000;    // skill ticks: 25 Hz of (sim) time
  std::chrono::milliseconds tick_timeout{1000};
  // How long a skill process may take to expand a compound: TaskPlan plans there (Fast
  // Downward, seconds on a large world; its first plan also imports the planner).
  std::chrono::milliseconds expand_timeout{30000};
  std::vector<std::string> ontology_files;  // for the world replica (conditions, grounding)
  std::string start_at_first_tick;           // "TYPE" or "TYPE:LABEL": a task started at the first tick
  int64_t end_session_after_frames = -1;     // lockstep: when that task ends, end the session this many frames later
  std::string robot;                         // element id of the agent this manager drives
  std::string robot_label;                   // else its label (the robot's name, --robot NAME)
  // Wall clock: a skill process without a heartbeat for this long has its skills dropped.
  std::chrono::milliseconds liveness_timeout{3000};
};

struct Task {
  int64_t id = 0;
  std::string type, label;
  Blackboard blackboard;
  std::unique_ptr<TaskContext> ctx;
  std::unique_ptr<Node> root;
  int64_t ticks = 0;
  bool stop_requested = false;
  bool paused = false;
  bool step_once = false;  // while paused: tick once at the next tick time
};

class Manager {
 public:
  Manager(Bus& bus, ManagerOptions options);
  RunResult run_until(std::function<bool()> should_stop);
  const Registry& registry() const { return registry_; }
  // How each finished task ended: id -> "Success: message" / "Failure: message".
  const std::map<int64_t, std::string>& results() const { return results_; }
  // Execute ticks not sent: the primitive was idle (skill_tick_reply_t.idle_until_ns).
  int64_t idle_ticks() const { return idle_ticks_; }
  // Ticks sent to skill processes, by action: START, EXECUTE, PREEMPT, END.
  const std::array<int64_t, 4>& ticks_sent() const { return ticks_sent_; }

 private:
  void on_frame(int64_t frame, int64_t sim_time_ns);
  void end_if_finished(std::map<int64_t, std::unique_ptr<Task>>::iterator& it);
  // How a task ended; the --start task's end may end the lockstep session.
  void record_result(int64_t id, const std::string& result);
  std::string unknown_skill_error(const std::string& type, const std::string& label) const;
  void begin(const skillbus_msgs::skill_start_t& req, int64_t id);
  void tick(Task& t);
  void publish_progress(const Task& t);
  // The final progress of a task that ended without a tree (stopped while queued, refused at
  // its start): one node, so watchers see its end as they see any other.
  void publish_end_without_tree(int64_t id, const std::string& type, const std::string& message);
  // Keeps p as the task's latest progress (for SKILL.tasks); a finished task's is kept
  // among the last kFinishedKept.
  void remember(skillbus_msgs::skill_progress_t p);
  skillbus_msgs::skill_progress_list_t tasks_reply(int64_t task) const;
  RpcClient& client(const std::string& area);

  Bus& bus_;
  ManagerOptions opt_;
  Registry registry_;
  LockstepParticipant participant_;
  WorldReplica world_;
  RpcServer rpc_;
  std::map<std::string, std::unique_ptr<RpcClient>> clients_;
  std::map<int64_t, std::unique_ptr<Task>> tasks_;
  int64_t frame_ = -1, sim_time_ns_ = 0;  // of the tick in progress
  void check_frame_period(int64_t frame, int64_t sim_time_ns) const;
  // Started tasks wait here for the next tick time; pause, resume and step apply to them as
  // to running ones (a task paused before it began begins paused).
  struct QueuedStart {
    int64_t id = 0;
    skillbus_msgs::skill_start_t req;
    bool paused = false, step_once = false;
  };
  std::deque<QueuedStart> starts_;
  // This run's identity in the managers' directory under lockstep (the wall clock's is
  // Liveness's incarnation): the system clock at start, never read for behaviour.
  const int64_t run_id_ = std::chrono::duration_cast<std::chrono::nanoseconds>(
                              std::chrono::system_clock::now().time_since_epoch()).count();
  std::deque<std::pair<int64_t, std::string>> stopped_queued_;  // stopped before they began: (task, type)
  int64_t next_task_ = 1;
  std::map<int64_t, std::string> results_;
  int64_t idle_ticks_ = 0;
  std::array<int64_t, 4> ticks_sent_{};
  static constexpr size_t kFinishedKept = 20;
  std::map<int64_t, skillbus_msgs::skill_progress_t> latest_;  // running and recently finished tasks
  std::string progress_channel_ = channel("SB_SKILL_PROGRESS");  // (named once: published every tick)
  std::deque<int64_t> finished_;  // ids in latest_ that ended, oldest first
  int64_t start_task_ = -1;  // the --start task's id
  std::unique_ptr<Liveness> liveness_;  // wall clock only
  std::unique_ptr<Directory> directory_;  // answers "which managers are there"
  std::chrono::steady_clock::time_point last_world_try_{};
};

}  // namespace skillbus::skills
