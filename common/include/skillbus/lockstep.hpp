// Lockstep: the clock master and its participants (protocol in docs/lockstep.md).
//
// Frame n:
//   master:       on_frame_start(n) publishes its state stamped n, then clock(n) with
//                 the counts of everything published since the previous clock;
//   participant:  waits until it holds every announced message on its channels,
//                 delivers them in canonical order (frame, sender, seq), runs
//                 on_frame(n), publishes stamped n, acks n with its counts and digest;
//   master:       when all acks for n are in, delivers the participants' outputs to its
//                 own subscriptions in canonical order, runs on_frame_end(n) (apply
//                 commands, step physics) and folds every digest into the session digest.
// Nothing here reads the wall clock for behaviour; timeouts only detect faults, and a
// fault stops the run with an error that names the participant, or channel and frame.
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "skillbus/lockstep_frame.hpp"
#include "skillbus_msgs/lockstep_clock_t.hpp"

namespace skillbus {

using FrameCallback = std::function<void(int64_t frame, int64_t sim_time_ns)>;
using MessageHandler = std::function<void(const StampedMessage&)>;

struct MasterConfig {
  std::string name = "clock";
  std::vector<std::string> participants;  // expected, by name
  int64_t frame_period_ns = 10'000'000;   // 10 ms
  int64_t frames = -1;                    // how many frames to run; -1 = until stop()
  std::chrono::milliseconds join_timeout{10000};
  std::chrono::milliseconds ack_timeout{5000};
  // Participants whose frames may take longer (the map server inserting a whole depth
  // capture in one frame: seconds on a busy machine), each with its own ack timeout.
  // The others are still declared dead after ack_timeout; while the master waits it
  // resends the clock, which tells the participants that acked that it is alive.
  std::map<std::string, std::chrono::milliseconds> ack_timeout_of;
  std::chrono::milliseconds message_timeout{2000};
  std::chrono::milliseconds resend_interval{250};  // re-publish an unacknowledged clock
  // Once its own work of the frame is done (on_clock_sent), how long the master polls for
  // the acks without sleeping before it sleeps on the socket. On a core of its own nothing
  // else needs the time, and on a virtual machine a sleeping receiver on another core costs
  // each sender about 30 us to wake and itself as long to run again (docs/lockstep.md,
  // "Polling for the acks"). 0: sleep at once.
  std::chrono::microseconds ack_poll{0};
  // Asked to end (lockstep_end_t): with names here, the session ends once each of them has
  // asked, at the latest frame asked for (several robots, each ending its own task); empty:
  // at the first frame anyone asks for.
  std::vector<std::string> end_when_asked_by;
};

class LockstepMaster {
 public:
  LockstepMaster(Bus& bus, MasterConfig config);
  ~LockstepMaster();

  // Lockstep subscription: participants' messages on this exact channel are delivered
  // after all acks of their frame, in canonical order, before on_frame_end.
  void subscribe(const std::string& channel, MessageHandler handler);

  // Publish state for the current frame (call from on_frame_start).
  template <class T>
  void publish(const std::string& ch, const T& msg) { outbox_.publish(ch, msg); }

  FrameCallback on_frame_start;
  // Runs once the clock of the frame is out, while the participants work on the frame
  // (before their acks are awaited): work that needs nothing from this frame's
  // participants, such as a physics step on the previous frame's commands, overlaps
  // with theirs. It must not publish (the frame's counts are already announced).
  FrameCallback on_clock_sent;
  FrameCallback on_frame_end;

  RunResult run();
  void stop(const std::string& reason = "");  // from a callback: end after this frame
  // A stop asked from outside (SIGTERM, Ctrl-C: apps::stop_requested), checked in every
  // wait as well as between frames: a master waiting for a join, an ack or a message ends
  // at once (the frame in hand unfinished and not counted), and tells the participants
  // that the session is over, as a stop() does.
  std::function<bool()> interrupted;
  const BadInputCounter& bad_input() const { return bad_; }
  const MasterConfig& config() const { return cfg_; }
  // Where frames' wall time went, for benchmarks (never behaviour): per participant the
  // summed time from the clock going out to its ack being read, and the summed time of the
  // whole ack wait (the slowest participant of each frame). While on_clock_sent runs (the
  // physics' step) no ack is read, so an ack that came during it counts until its end:
  // held_seconds is, per participant, only what its ack came after on_clock_sent returned
  // (how long it held the frame up past the master's own work), and ended_by how many
  // frames its ack was the last one of, among the frames whose acks were not all in when
  // on_clock_sent returned.
  const std::map<std::string, double>& ack_seconds() const { return ack_seconds_; }
  const std::map<std::string, double>& held_seconds() const { return held_seconds_; }
  const std::map<std::string, int64_t>& ended_by() const { return ended_by_; }
  double wait_seconds() const { return wait_seconds_; }

 private:
  bool wait_for_joins(std::string& error);
  bool run_frame(int64_t frame, int64_t sim_time, std::vector<ChannelCount>& carried, std::string& error);
  void publish_stop(int64_t frame, int64_t sim_time, const std::string& reason);
  skillbus_msgs::lockstep_clock_t make_clock(int64_t frame, int64_t sim_time) const;
  void on_join(const uint8_t* d, size_t n, const std::string& ch);
  void on_ack(const uint8_t* d, size_t n, const std::string& ch);

  Bus& bus_;
  MasterConfig cfg_;
  std::vector<std::string> expected_;  // sorted
  BadInputCounter bad_;
  FrameOutbox outbox_;
  FrameInbox inbox_;
  std::set<std::string> stamped_channels_;
  std::map<std::string, MessageHandler> handlers_;
  std::vector<int> subs_;
  std::set<std::string> joined_;
  struct Ack {
    std::vector<ChannelCount> counts;
    Digest digest{};
    std::string error;
  };
  int64_t awaiting_frame_ = -1;
  std::map<std::string, Ack> acks_;
  Sha256 session_;
  Digest session_digest_{};
  std::vector<std::chrono::milliseconds> ack_timeouts_;  // per participant, in expected_'s order
  // Per participant, in expected_'s order: its last sign of life while a frame's acks are
  // awaited (a join sent while it works on the frame: it is alive, however long it takes).
  std::vector<std::chrono::steady_clock::time_point> alive_at_;
  std::vector<int64_t> pid_of_;  // the pid each joined with: a join from another is a restart, no sign of life
  // A participant started again (a join from another pid) ends the session at once: what
  // it was told before (a skill process's registration with the manager, before frame 0 as
  // well) is lost with the process. The error, once one is heard; the latest frame begun.
  std::string restarted_;
  int64_t frame_begun_ = -1;
  bool stop_requested_ = false;
  std::string stop_reason_;
  int64_t end_at_ = -1;  // a participant asked to end after this frame (lockstep_end_t)
  std::map<std::string, int64_t> end_asked_;  // with end_when_asked_by: who asked, for which frame
  std::chrono::steady_clock::time_point clock_sent_{};
  std::chrono::steady_clock::time_point own_work_done_{};  // on_clock_sent returned (or the clock went out)
  bool polling() const;  // still polling for this frame's acks (MasterConfig::ack_poll)
  bool asked_to_stop();  // stop() or interrupted(), remembered
  std::string last_acker_;
  std::map<std::string, double> ack_seconds_;
  std::map<std::string, double> held_seconds_;
  std::map<std::string, int64_t> ended_by_;
  double wait_seconds_ = 0;
};

enum class ClockMode { Lockstep, WallClock };

struct ParticipantConfig {
  std::string name;
  std::string kind = "cpp";
  ClockMode mode = ClockMode::Lockstep;
  std::chrono::milliseconds message_timeout{2000};  // announced messages must arrive within
  std::chrono::milliseconds clock_timeout{10000};   // a silent master is an error after
  std::chrono::milliseconds join_interval{100};
  int64_t wall_frame_period_ns = 10'000'000;        // wall-clock mode only
  int64_t wall_frames = -1;                         // wall-clock mode: -1 = until stop()
};

class LockstepParticipant {
 public:
  LockstepParticipant(Bus& bus, ParticipantConfig config);
  ~LockstepParticipant();

  void subscribe(const std::string& channel, MessageHandler handler);

  // Publish for the current frame (call from on_frame or a message handler).
  template <class T>
  void publish(const std::string& ch, const T& msg) { outbox_.publish(ch, msg); }

  FrameCallback on_frame;

  RunResult run();
  void stop();
  // A stop asked from outside (SIGTERM, Ctrl-C: apps::stop_requested), checked in every
  // wait as well as between frames: a participant waiting to join, for a clock or for a
  // frame's messages ends at once (the frame in hand is not acked; the master names it
  // when its ack timeout passes), instead of when the master or its timeout ends it.
  std::function<bool()> interrupted;
  // Asks the master to end the session `after_frames` after the current frame (published
  // with this frame, so the end is at a frame the participant's work decides).
  void request_end(int64_t after_frames, const std::string& why);
  int64_t frame() const { return outbox_.frame(); }
  // The last frame this participant finished and acknowledged (-1 before the first).
  int64_t completed_frame() const { return completed_; }
  // Runs after each frame's ack (lockstep): e.g. answering the RPC requests that waited
  // for that frame (RpcServer::retry_deferred).
  std::function<void(int64_t frame)> after_frame;
  const BadInputCounter& bad_input() const { return bad_; }
  const std::string& name() const { return cfg_.name; }

 private:
  RunResult run_lockstep();
  RunResult run_wall_clock();
  void on_clock(const uint8_t* d, size_t n, const std::string& ch);
  void send_ack(int64_t frame, int64_t sim_time, const std::string& error);
  bool asked_to_stop();  // stop() or interrupted(), remembered

  Bus& bus_;
  ParticipantConfig cfg_;
  BadInputCounter bad_;
  FrameOutbox outbox_;
  FrameInbox inbox_;
  std::set<std::string> stamped_channels_;
  std::map<std::string, MessageHandler> handlers_;
  std::vector<int> subs_;
  struct Clock {
    int64_t frame = -1, sim_time_ns = 0;
    std::vector<ChannelCount> counts;
    bool stop = false;
    std::string stop_reason;
  };
  std::string master_;  // name of the master whose clock we follow (from the first clock)
  std::string ack_channel_ = ack_channel();  // (named once: an ack goes out every frame)
  std::chrono::steady_clock::time_point master_heard_{};  // the last resend of the clock we acked
  bool have_clock_ = false;
  int64_t completed_ = -1;
  Clock next_clock_;
  bool stop_seen_ = false;
  std::string master_restarted_;  // the error, once a restarted master's join phase is heard in a session
  std::string stop_reason_;
  int64_t last_acked_ = -1;
  int64_t current_ = -1;  // the frame being worked on (its clock may be resent meanwhile)
  Bytes join_;            // its join, sent again as a sign of life while it works on a frame
  Bytes last_ack_;
  Sha256 running_;
  Digest running_digest_{};
  bool stop_requested_ = false;
};

}  // namespace skillbus
