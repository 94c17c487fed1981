#include <unistd.h>

#include <algorithm>
#include <thread>

#include "skillbus/lockstep.hpp"

#include "skillbus_msgs/lockstep_ack_t.hpp"
#include "skillbus_msgs/lockstep_clock_t.hpp"
#include "skillbus_msgs/lockstep_end_t.hpp"
#include "skillbus_msgs/lockstep_join_t.hpp"

namespace skillbus {
namespace {
using steady = std::chrono::steady_clock;
using std::chrono::milliseconds;
}  // namespace

LockstepParticipant::LockstepParticipant(Bus& bus, ParticipantConfig config)
    : bus_(bus),
      cfg_(std::move(config)),
      bad_("lockstep " + cfg_.name),
      outbox_(bus, cfg_.name),
      inbox_(cfg_.name, bad_) {
  if (cfg_.name.empty()) throw std::invalid_argument("a lockstep participant needs a name");
  if (cfg_.mode == ClockMode::Lockstep)
    subs_.push_back(bus_.subscribe(clock_channel(), [this](const std::string& ch, const uint8_t* d, size_t n) {
      on_clock(d, n, ch);
    }));
}

LockstepParticipant::~LockstepParticipant() {
  for (int s : subs_) bus_.unsubscribe(s);
}

void LockstepParticipant::subscribe(const std::string& ch, MessageHandler handler) {
  handlers_[ch] = std::move(handler);
  if (!stamped_channels_.insert(ch).second) return;
  subs_.push_back(bus_.subscribe(ch, [this](const std::string& c, const uint8_t* d, size_t n) {
    if (cfg_.mode == ClockMode::Lockstep) return inbox_.add(c, d, n);
    // Wall-clock mode: no counts to wait for; deliver on arrival.
    StampedMessage m{c, {}, Bytes(d, d + n)};
    if (!peek_stamp(d, n, m.stamp)) return bad_.record(c, "no lockstep header (frame, sender, seq)", n);
    if (m.stamp.sender == cfg_.name) return;
    try {
      handlers_[c](m);
    } catch (const std::exception& e) {  // counted, and logged rate-limited, per channel
      bad_.record(c, std::string("refused by its handler: ") + e.what(), n);
    }
  }));
}

void LockstepParticipant::request_end(int64_t after_frames, const std::string& why) {
  skillbus_msgs::lockstep_end_t e{};
  e.after_frames = after_frames;
  e.why = why;
  publish(end_channel(), e);
}

void LockstepParticipant::stop() { stop_requested_ = true; }

bool LockstepParticipant::asked_to_stop() {
  if (!stop_requested_ && interrupted && interrupted()) stop_requested_ = true;
  return stop_requested_;
}

void LockstepParticipant::on_clock(const uint8_t* d, size_t n, const std::string& ch) {
  skillbus_msgs::lockstep_clock_t c{};
  if (!decode_msg(d, n, c)) return bad_.record(ch, "not a lockstep_clock_t", n);
  // Only the clock of our session counts: it lists us, and comes from the master that
  // sent the first one we accepted.
  if (std::find(c.participants.begin(), c.participants.end(), cfg_.name) == c.participants.end())
    return bad_.record(ch, "a clock from '" + c.header.sender + "' that does not list " + cfg_.name, n);
  if (master_.empty()) master_ = c.header.sender;
  if (c.header.sender != master_)
    return bad_.record(ch, "a clock from '" + c.header.sender + "', not from our master '" + master_ + "'", n);
  if (c.stop) {
    stop_seen_ = true;
    stop_reason_ = c.stop_reason;
    return;
  }
  if (c.header.frame < 0) {  // the master waits for participants to join
    if (last_acked_ < 0 && current_ < 0 && !have_clock_) {
      master_heard_ = steady::now();  // before our first frame: it is alive, and so we wait on
      return;
    }
    // Within a session: the master started again (killed and restarted), and the session
    // is lost. Said now, naming it, rather than after the clock timeout.
    master_restarted_ = "lockstep: master " + master_ + " started again after frame " + std::to_string(last_acked_) +
                        " (it waits for participants to join): this session is lost";
    stop_seen_ = true;
    have_clock_ = false;
    return;
  }
  if (c.header.frame == last_acked_ && !last_ack_.empty()) {
    // The master resends the clock while a participant is still at work on the frame: it
    // is alive, so this one waits on (a frame may take a slow participant long).
    master_heard_ = steady::now();
    bus_.publish(ack_channel_, last_ack_.data(), last_ack_.size());  // our ack was lost, or not yet counted
    return;
  }
  if (c.header.frame == current_ && current_ == last_acked_ + 1) {
    // The master resends the clock of the frame this participant works on (a long one:
    // an expansion, a plan): it is told so by a join, a sign of life, or it would take
    // the participant for dead after its ack timeout.
    if (!join_.empty()) bus_.publish(join_channel(), join_.data(), join_.size());
    return;
  }
  if (c.header.frame <= last_acked_ || c.header.frame == current_) return;  // resend of the frame in hand
  if (c.header.frame != last_acked_ + 1)
    return bad_.record(ch, "a clock for frame " + std::to_string(c.header.frame) + " while frame " +
                               std::to_string(last_acked_ + 1) + " is due", n);
  if (have_clock_) return;  // a resend of the clock we already hold
  have_clock_ = true;
  next_clock_.frame = c.header.frame;
  next_clock_.sim_time_ns = c.header.sim_time_ns;
  next_clock_.counts = std::move(c.counts);
}

void LockstepParticipant::send_ack(int64_t frame, int64_t sim_time, const std::string& error) {
  skillbus_msgs::lockstep_ack_t a{};
  a.header.frame = frame;
  a.header.sim_time_ns = sim_time;
  a.header.sender = cfg_.name;
  a.header.seq = 0;
  a.counts = outbox_.counts();
  a.num_counts = static_cast<int32_t>(a.counts.size());
  const Digest d = outbox_.finish_frame();
  std::copy(d.begin(), d.end(), a.digest);
  a.error = error;
  last_ack_ = encode_msg(a);
  last_acked_ = frame;
  bus_.publish(ack_channel_, last_ack_.data(), last_ack_.size());
  running_.update(running_digest_.data(), running_digest_.size());
  running_.update(d.data(), d.size());
  running_digest_ = running_.finish();
}

RunResult LockstepParticipant::run() {
  return cfg_.mode == ClockMode::Lockstep ? run_lockstep() : run_wall_clock();
}

RunResult LockstepParticipant::run_lockstep() {
  RunResult r;
  auto wall_start = steady::now();
  auto fail = [&](const std::string& e) {
    r.ok = false;
    r.error = e;
    SB_ERROR("lockstep " + cfg_.name, e);
  };

  // Join: announce ourselves until the first clock shows the master has started.
  skillbus_msgs::lockstep_join_t j{};
  j.participant = cfg_.name;
  j.kind = cfg_.kind;
  j.pid = ::getpid();
  join_ = encode_msg(j);
  auto last_event = steady::now();
  auto next_join = last_event;
  while (!have_clock_ && !stop_seen_) {
    if (asked_to_stop()) {
      SB_INFO("lockstep " + cfg_.name, "stopped before the first frame (asked to, while waiting for the master's clock)");
      return r;
    }
    const auto now = steady::now();
    if (now - std::max(last_event, master_heard_) > cfg_.clock_timeout) {
      fail("lockstep: joined, but no clock from the master, nor word that it waits for the others to join, within " +
           std::to_string(cfg_.clock_timeout.count() / 1000.0).substr(0, 4) + " s (no master on this bus?)");
      return r;
    }
    if (now >= next_join) {
      publish_msg(bus_, join_channel(), j);
      next_join = now + cfg_.join_interval;
    }
    bus_.handle(milliseconds(10));
  }
  wall_start = steady::now();

  // A stop asked while waiting (interrupted) ends the run at once: the frame in hand is not
  // acked. Said in the log, since the master only sees the ack missing.
  auto stopped_waiting = [&](const std::string& for_what) {
    SB_INFO("lockstep " + cfg_.name, "stopped after frame " << last_acked_ << " (asked to, while waiting for " << for_what
                                                               << ")");
  };
  while (!asked_to_stop()) {
    // Wait for the clock of the next frame.
    last_event = steady::now();
    while (!have_clock_ && !stop_seen_) {
      if (asked_to_stop()) break;
      if (steady::now() - std::max(last_event, master_heard_) > cfg_.clock_timeout) {
        fail("lockstep: no clock after frame " + std::to_string(last_acked_) + " within " +
             std::to_string(cfg_.clock_timeout.count() / 1000.0).substr(0, 4) + " s (master " + master_ + " gone?)");
        return r;
      }
      bus_.handle(milliseconds(50));
    }
    if (stop_requested_ && !have_clock_) {
      stopped_waiting("the clock of frame " + std::to_string(last_acked_ + 1));
      break;
    }
    if (stop_seen_ && !have_clock_) break;
    Clock clk = std::move(next_clock_);
    have_clock_ = false;
    current_ = clk.frame;

    // Wait until every message announced for this frame on our channels is here.
    const auto expected = expectations_for(clk.counts, stamped_channels_, cfg_.name);
    const auto deadline = steady::now() + cfg_.message_timeout;
    std::string miss;
    for (miss = inbox_.missing(expected); !miss.empty() && !stop_seen_; miss = inbox_.missing(expected)) {
      const auto left = std::chrono::duration_cast<milliseconds>(deadline - steady::now());
      if (left.count() <= 0 || asked_to_stop()) break;
      bus_.handle(std::min(left, milliseconds(50)));
    }
    if (stop_seen_) break;
    if (!miss.empty() && stop_requested_) {
      stopped_waiting("frame " + std::to_string(clk.frame) + "'s message on " + miss);
      break;
    }
    outbox_.begin_frame(clk.frame, clk.sim_time_ns);
    if (!miss.empty()) {
      const std::string e = "message lost on " + miss + " (noticed by " + cfg_.name + ")";
      send_ack(clk.frame, clk.sim_time_ns, e);
      fail("lockstep: " + e);
      return r;
    }
    std::string failure;
    try {
      for (const auto& m : inbox_.take(expected, clk.frame)) handlers_[m.channel](m);
      if (on_frame) on_frame(clk.frame, clk.sim_time_ns);
    } catch (const std::exception& e) {
      failure = std::string("frame handler failed: ") + e.what();
    }
    send_ack(clk.frame, clk.sim_time_ns, failure);
    if (!failure.empty()) {
      fail("lockstep: " + cfg_.name + " in frame " + std::to_string(clk.frame) + ": " + failure);
      return r;
    }
    ++r.frames;
    r.sim_time_ns = clk.sim_time_ns + 0;
    completed_ = clk.frame;
    if (after_frame) after_frame(clk.frame);
  }
  if (!master_restarted_.empty())
    fail(master_restarted_);
  else if (stop_seen_ && !stop_reason_.empty())
    fail("lockstep stopped by the master: " + stop_reason_);
  r.digest = running_digest_;
  r.wall_seconds = std::chrono::duration<double>(steady::now() - wall_start).count();
  return r;
}

RunResult LockstepParticipant::run_wall_clock() {
  RunResult r;
  const auto start = steady::now();
  auto anchor = start;  // frame 0's due time, moved on when the loop falls behind
  const auto period = std::chrono::nanoseconds(cfg_.wall_frame_period_ns);
  for (int64_t frame = 0; !asked_to_stop() && (cfg_.wall_frames < 0 || frame < cfg_.wall_frames); ++frame) {
    auto due = anchor + frame * period;
    // Behind by more than a frame (a long frame: an expansion, a planner, a stalled
    // machine): the frames missed are not run back to back, which would tick skills many
    // times in a few milliseconds with nobody else heard in between; the schedule starts
    // again from now, at the frame period.
    if (steady::now() - due > period) {
      anchor += steady::now() - due;
      due = anchor + frame * period;
    }
    for (auto now = steady::now(); now < due; now = steady::now())
      bus_.handle(std::chrono::ceil<milliseconds>(due - now));
    const int64_t sim_time = frame * cfg_.wall_frame_period_ns;
    outbox_.begin_frame(frame, sim_time);
    if (on_frame) on_frame(frame, sim_time);
    running_.update(running_digest_.data(), running_digest_.size());
    const Digest d = outbox_.finish_frame();
    running_.update(d.data(), d.size());
    running_digest_ = running_.finish();
    r.frames = frame + 1;
    r.sim_time_ns = sim_time;
  }
  r.digest = running_digest_;
  r.wall_seconds = std::chrono::duration<double>(steady::now() - start).count();
  return r;
}

}  // namespace skillbus
