#include <unistd.h>

#include <algorithm>
#include <stdexcept>
#include <thread>

#include "skillbus/lockstep.hpp"

#include "skillbus_msgs/lockstep_ack_t.hpp"
#include "skillbus_msgs/lockstep_clock_t.hpp"
#include "skillbus_msgs/lockstep_end_t.hpp"
#include "skillbus_msgs/lockstep_join_t.hpp"

namespace skillbus {
namespace {

using steady = std::chrono::steady_clock;
const char* kLog = "lockstep-master";

std::string join_names(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

double seconds(std::chrono::milliseconds d) { return static_cast<double>(d.count()) / 1000.0; }

std::string secs_text(std::chrono::milliseconds d) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f s", seconds(d));
  return buf;
}

}  // namespace

LockstepMaster::LockstepMaster(Bus& bus, MasterConfig config)
    : bus_(bus),
      cfg_(std::move(config)),
      expected_(cfg_.participants),
      bad_(kLog),
      outbox_(bus, cfg_.name),
      inbox_(cfg_.name, bad_) {
  std::sort(expected_.begin(), expected_.end());
  expected_.erase(std::unique(expected_.begin(), expected_.end()), expected_.end());
  auto& enders = cfg_.end_when_asked_by;
  std::sort(enders.begin(), enders.end());
  enders.erase(std::unique(enders.begin(), enders.end()), enders.end());
  // A name that is no participant would never ask: the session could end only by --frames.
  for (const auto& name : enders)
    if (!std::binary_search(expected_.begin(), expected_.end(), name))
      throw std::invalid_argument("end_when_asked_by names '" + name + "', who is not a participant");
  for (const auto& [name, timeout] : cfg_.ack_timeout_of) {
    if (!std::binary_search(expected_.begin(), expected_.end(), name))
      throw std::invalid_argument("an ack timeout for '" + name + "', who is not a participant");
    if (timeout.count() <= 0) throw std::invalid_argument("the ack timeout for '" + name + "' must be positive");
  }
  // Each participant's ack timeout, in expected_'s order (looked up once, not every frame).
  for (const auto& p : expected_) {
    const auto it = cfg_.ack_timeout_of.find(p);
    ack_timeouts_.push_back(it == cfg_.ack_timeout_of.end() ? cfg_.ack_timeout : it->second);
  }
  alive_at_.assign(expected_.size(), {});
  pid_of_.assign(expected_.size(), 0);
  subs_.push_back(bus_.subscribe(join_channel(), [this](const std::string& ch, const uint8_t* d, size_t n) {
    on_join(d, n, ch);
  }));
  subs_.push_back(bus_.subscribe(ack_channel(), [this](const std::string& ch, const uint8_t* d, size_t n) {
    on_ack(d, n, ch);
  }));
  subscribe(end_channel(), [this](const StampedMessage& m) {
    skillbus_msgs::lockstep_end_t e{};
    if (!decode_msg(m.data.data(), m.data.size(), e) || e.after_frames < 0)
      return bad_.record(m.channel, "not a lockstep_end_t", m.data.size());
    const int64_t at = m.stamp.frame + e.after_frames;
    const auto& needed = cfg_.end_when_asked_by;
    if (needed.empty()) {
      if (end_at_ < 0 || at < end_at_) {
        end_at_ = at;
        SB_INFO(kLog, m.stamp.sender << " asks to end the session after frame " << at << ": " << e.why);
      }
      return;
    }
    if (std::find(needed.begin(), needed.end(), m.stamp.sender) == needed.end()) {
      SB_INFO(kLog, m.stamp.sender << " asks to end the session (" << e.why << "); it ends when "
                                   << needed.size() << " named participants have asked");
      return;
    }
    if (!end_asked_.emplace(m.stamp.sender, at).second) return;  // (its first ask counts)
    SB_INFO(kLog, m.stamp.sender << " asks to end the session after frame " << at << ": " << e.why << " ("
                                 << end_asked_.size() << " of " << needed.size() << ")");
    if (end_asked_.size() == needed.size())
      for (const auto& [who, frame] : end_asked_) end_at_ = std::max(end_at_, frame);
  });
}

LockstepMaster::~LockstepMaster() {
  for (int s : subs_) bus_.unsubscribe(s);
}

void LockstepMaster::subscribe(const std::string& ch, MessageHandler handler) {
  handlers_[ch] = std::move(handler);
  if (stamped_channels_.insert(ch).second)
    subs_.push_back(bus_.subscribe(ch, [this](const std::string& c, const uint8_t* d, size_t n) { inbox_.add(c, d, n); }));
}

void LockstepMaster::stop(const std::string& reason) {
  stop_requested_ = true;
  stop_reason_ = reason;
}

bool LockstepMaster::asked_to_stop() {
  if (!stop_requested_ && interrupted && interrupted()) stop_requested_ = true;
  return stop_requested_;
}

void LockstepMaster::on_join(const uint8_t* d, size_t n, const std::string& ch) {
  skillbus_msgs::lockstep_join_t j{};
  if (!decode_msg(d, n, j)) return bad_.record(ch, "not a lockstep_join_t", n);
  if (!std::binary_search(expected_.begin(), expected_.end(), j.participant)) {
    if (joined_.insert("?" + j.participant).second)
      SB_WARN(kLog, "ignoring participant '" << j.participant << "' (pid " << j.pid
                                             << "): not among the expected " << join_names(expected_));
    return;
  }
  if (joined_.insert(j.participant).second)
    SB_INFO(kLog, "participant '" << j.participant << "' (" << j.kind << ", pid " << j.pid << ") joined");
  // While a frame's acks are awaited, a join from the process that joined is a participant
  // at work on the frame that heard its clock again: alive, so its ack timeout runs from
  // now. A join from another process of that name is a restart (the one that joined may be
  // dead): no sign of life.
  const auto i = static_cast<size_t>(std::lower_bound(expected_.begin(), expected_.end(), j.participant) -
                                     expected_.begin());
  if (pid_of_[i] == 0) pid_of_[i] = j.pid;
  if (j.pid != 0 && j.pid != pid_of_[i] && restarted_.empty())
    restarted_ = "lockstep: participant(s) " + j.participant + " started again (pid " + std::to_string(pid_of_[i]) +
                 ", now " + std::to_string(j.pid) + ") " +
                 (frame_begun_ < 0 ? std::string("before frame 0") : "in frame " + std::to_string(frame_begun_)) +
                 ": what was set up with it before is lost, and this session with it (or a second process uses "
                 "its name)";
  if (awaiting_frame_ >= 0 && j.pid == pid_of_[i]) alive_at_[i] = steady::now();
}

void LockstepMaster::on_ack(const uint8_t* d, size_t n, const std::string& ch) {
  skillbus_msgs::lockstep_ack_t a{};
  if (!decode_msg(d, n, a)) return bad_.record(ch, "not a lockstep_ack_t", n);
  if (a.header.frame != awaiting_frame_) return;  // a resent ack of an earlier frame
  if (!std::binary_search(expected_.begin(), expected_.end(), a.header.sender)) return;
  if (!acks_.count(a.header.sender)) {
    const auto now = steady::now();
    ack_seconds_[a.header.sender] += std::chrono::duration<double>(now - clock_sent_).count();
    // An ack read before the bus first ran dry after on_clock_sent may have come during it
    // (it waited in the socket): it held nothing up. (A bus that cannot tell says now.)
    if (bus_.caught_up_at() > own_work_done_) {
      held_seconds_[a.header.sender] += std::chrono::duration<double>(now - own_work_done_).count();
      last_acker_ = a.header.sender;
    } else {
      held_seconds_.emplace(a.header.sender, 0.0);
    }
  }
  Ack& ack = acks_[a.header.sender];
  ack.counts = std::move(a.counts);
  std::copy(std::begin(a.digest), std::end(a.digest), ack.digest.begin());
  ack.error = std::move(a.error);
}

bool LockstepMaster::polling() const {
  return cfg_.ack_poll.count() > 0 && steady::now() - own_work_done_ < cfg_.ack_poll;
}

bool LockstepMaster::wait_for_joins(std::string& error) {
  const auto deadline = steady::now() + cfg_.join_timeout;
  auto all_joined = [&] {
    return std::all_of(expected_.begin(), expected_.end(), [&](const std::string& p) { return joined_.count(p) > 0; });
  };
  // Those who joined wait for their first clock with their own timeout, which a slow
  // start of another (a library's warm-up on a loaded machine) can outlast: the clock of
  // frame -1, resent meanwhile, tells them the master is alive and waiting. It starts no
  // frame; a participant only notes it.
  skillbus_msgs::lockstep_clock_t waiting = make_clock(-1, 0);
  waiting.stop = false;
  const Bytes waiting_clock = encode_msg(waiting);
  auto say_waiting_at = steady::now();
  while (!all_joined() || !restarted_.empty()) {
    if (!restarted_.empty()) {
      error = restarted_;
      return false;
    }
    if (asked_to_stop()) {
      std::vector<std::string> missing;
      for (const auto& p : expected_)
        if (!joined_.count(p)) missing.push_back(p);
      SB_INFO(kLog, "stopped before the first frame (asked to, while " << join_names(missing) << " had not joined)");
      return false;  // (no error: a stop asked for)
    }
    if (steady::now() >= say_waiting_at) {
      bus_.publish(clock_channel(), waiting_clock.data(), waiting_clock.size());
      say_waiting_at = steady::now() + cfg_.resend_interval;
    }
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - steady::now());
    if (left.count() <= 0) {
      std::vector<std::string> missing;
      for (const auto& p : expected_)
        if (!joined_.count(p)) missing.push_back(p);
      error = "lockstep: participant(s) " + join_names(missing) + " never joined within " +
              secs_text(cfg_.join_timeout);
      return false;
    }
    bus_.handle(std::min({left, cfg_.resend_interval, std::chrono::milliseconds(50)}));
  }
  return true;
}

skillbus_msgs::lockstep_clock_t LockstepMaster::make_clock(int64_t frame, int64_t sim_time) const {
  skillbus_msgs::lockstep_clock_t c{};
  c.header.frame = frame;
  c.header.sim_time_ns = sim_time;
  c.header.sender = cfg_.name;
  c.frame_period_ns = cfg_.frame_period_ns;
  c.participants = expected_;
  c.num_participants = static_cast<int32_t>(expected_.size());
  return c;
}

void LockstepMaster::publish_stop(int64_t frame, int64_t sim_time, const std::string& reason) {
  skillbus_msgs::lockstep_clock_t c = make_clock(frame, sim_time);
  c.stop = true;
  c.stop_reason = reason;
  // The stop is not acknowledged; send it a few times so a lost datagram does not
  // leave participants waiting for their clock timeout.
  for (int i = 0; i < 3; ++i) {
    publish_msg(bus_, clock_channel(), c);
    if (i < 2) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

bool LockstepMaster::run_frame(int64_t frame, int64_t sim_time, std::vector<ChannelCount>& carried,
                               std::string& error) {
  outbox_.begin_frame(frame, sim_time);
  try {
    if (on_frame_start) on_frame_start(frame, sim_time);
  } catch (const std::exception& e) {
    error = "lockstep: master " + cfg_.name + " failed to start frame " + std::to_string(frame) + ": " + e.what();
    return false;
  }

  skillbus_msgs::lockstep_clock_t c = make_clock(frame, sim_time);
  c.counts = carried;
  for (auto& own : outbox_.counts()) c.counts.push_back(own);
  c.num_counts = static_cast<int32_t>(c.counts.size());
  c.stop = false;
  const Bytes clock = encode_msg(c);

  acks_.clear();
  awaiting_frame_ = frame_begun_ = frame;
  const auto start = steady::now();
  clock_sent_ = own_work_done_ = start;
  auto resend_at = start;
  while (acks_.size() < expected_.size()) {
    const auto now = steady::now();
    // The earliest deadline among the participants still to ack, and who is past theirs.
    auto deadline = steady::time_point::max();
    std::vector<std::string> late;
    std::chrono::milliseconds late_after{0};
    for (size_t i = 0; i < expected_.size(); ++i)
      if (!acks_.count(expected_[i])) {
        const auto since = std::max(start, alive_at_[i]);  // the clock, or its last sign of life
        deadline = std::min(deadline, since + ack_timeouts_[i]);
        if (now - since >= ack_timeouts_[i]) {
          late.push_back(expected_[i]);
          late_after = ack_timeouts_[i];
        }
      }
    if (!restarted_.empty()) {
      error = restarted_;
      return false;
    }
    if (!late.empty()) {
      error = "lockstep: no ack for frame " + std::to_string(frame) + " from participant(s) " + join_names(late) +
              " within " + secs_text(late_after);
      return false;
    }
    if (asked_to_stop()) {  // the frame stays unfinished: not counted, not in the session digest
      std::vector<std::string> waiting;
      for (const auto& p : expected_)
        if (!acks_.count(p)) waiting.push_back(p);
      SB_INFO(kLog, "stopped in frame " << frame << " (asked to, while waiting for the ack of " << join_names(waiting)
                                        << ")");
      return false;  // (no error: a stop asked for)
    }
    if (now >= resend_at) {
      const bool first = resend_at == start;
      bus_.publish(clock_channel(), clock.data(), clock.size());
      resend_at = now + cfg_.resend_interval;
      if (first && on_clock_sent) {
        try {
          on_clock_sent(frame, sim_time);
          own_work_done_ = steady::now();
        } catch (const std::exception& e) {
          error = "lockstep: master " + cfg_.name + " failed in frame " + std::to_string(frame) + ": " + e.what();
          return false;
        }
        resend_at = std::max(resend_at, steady::now() + std::chrono::milliseconds(1));
      }
    }
    if (polling()) {
      bus_.handle(std::chrono::milliseconds(0));
      continue;
    }
    const auto wait = std::chrono::duration_cast<std::chrono::milliseconds>(std::min(resend_at, deadline) -
                                                                             steady::now());
    bus_.handle(std::max(wait, std::chrono::milliseconds(0)));
  }
  awaiting_frame_ = -1;
  wait_seconds_ += std::chrono::duration<double>(steady::now() - start).count();
  if (!last_acker_.empty()) ++ended_by_[last_acker_];
  last_acker_.clear();
  for (const auto& [name, ack] : acks_)
    if (!ack.error.empty()) {
      // A lost message is the sender's (or its link's) failure, not that of who noticed it.
      const std::string sender = sender_of_missing(ack.error);
      error = sender.empty() || sender == name
                  ? "lockstep: participant " + name + " failed in frame " + std::to_string(frame) + ": " + ack.error
                  : "lockstep: participant(s) " + sender + ": " + ack.error;
      return false;
    }

  // Everything the participants published in this frame, as their acks announce it.
  carried.clear();
  for (const auto& [name, ack] : acks_)
    for (const auto& cc : ack.counts) carried.push_back(cc);
  const auto expected = expectations_for(carried, stamped_channels_, cfg_.name);
  const auto msg_deadline = steady::now() + cfg_.message_timeout;
  for (std::string miss = inbox_.missing(expected); !miss.empty(); miss = inbox_.missing(expected)) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(msg_deadline - steady::now());
    if (left.count() <= 0) {
      error = "lockstep: participant(s) " + sender_of_missing(miss) + ": message lost on " + miss +
              " (noticed by master " + cfg_.name + ")";
      return false;
    }
    if (asked_to_stop()) {
      SB_INFO(kLog, "stopped in frame " << frame << " (asked to, while waiting for " << miss << ")");
      return false;  // (no error: a stop asked for)
    }
    bus_.handle(polling() ? std::chrono::milliseconds(0) : std::min(left, std::chrono::milliseconds(50)));
  }
  try {
    for (const auto& m : inbox_.take(expected, frame + 1)) {
      auto h = handlers_.find(m.channel);
      if (h != handlers_.end()) h->second(m);
    }
    if (on_frame_end) on_frame_end(frame, sim_time);
  } catch (const std::exception& e) {
    error = "lockstep: master " + cfg_.name + " failed to end frame " + std::to_string(frame) + ": " + e.what();
    return false;
  }

  // Session digest: previous digest, frame, the master's own output, then every
  // participant's frame digest in name order (never arrival order).
  session_.update(session_digest_.data(), session_digest_.size());
  session_.update_i64(frame);
  const Digest own = outbox_.finish_frame();
  session_.update(own.data(), own.size());
  for (const auto& [name, ack] : acks_) {
    session_.update_str(name);
    session_.update(ack.digest.data(), ack.digest.size());
  }
  session_digest_ = session_.finish();
  return true;
}

RunResult LockstepMaster::run() {
  RunResult r;
  auto wall_start = steady::now();
  std::string error;
  int64_t frame = 0, sim_time = 0;
  if (wait_for_joins(error)) {
    wall_start = steady::now();  // the figures are about frames, not about start-up
    SB_INFO(kLog, "all " << expected_.size() << " participant(s) joined; starting frames of "
                         << cfg_.frame_period_ns / 1e6 << " ms");
    std::vector<ChannelCount> carried;
    while ((cfg_.frames < 0 || frame < cfg_.frames) && !asked_to_stop()) {
      if (!run_frame(frame, sim_time, carried, error)) break;
      if (end_at_ >= 0 && frame >= end_at_) stop_requested_ = true;  // a normal end, asked for
      ++frame;
      sim_time += cfg_.frame_period_ns;
    }
  }
  r.ok = error.empty();
  r.error = error;
  r.frames = frame;
  r.sim_time_ns = sim_time;
  r.digest = session_digest_;
  if (!r.ok) SB_ERROR(kLog, error);
  publish_stop(frame, sim_time, r.ok ? stop_reason_ : error);
  r.wall_seconds = std::chrono::duration<double>(steady::now() - wall_start).count();
  return r;
}

}  // namespace skillbus
