#include "quiet_frames.hpp"

#include <arpa/inet.h>
#include <lcm/lcm.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <system_error>

#include "skillbus_msgs/lockstep_ack_t.hpp"
#include "skillbus_msgs/lockstep_clock_t.hpp"

namespace skillbus::native {

namespace {

constexpr size_t kMaxDatagram = 65536;
constexpr size_t kMaxChannel = 63;  // LCM_MAX_CHANNEL_NAME_LENGTH
constexpr uint8_t kShortMagic[4] = {'L', 'C', '0', '2'};
// More verified latest-only messages than this waiting for their clocks is no frame's
// traffic (a flood): Python takes them, and its inbox's rules, over.
constexpr size_t kMaxHeld = 4096;

int64_t be64(const uint8_t* p) {
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | p[i];
  return static_cast<int64_t>(v);
}

int32_t be32(const uint8_t* p) {
  return static_cast<int32_t>((uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | p[3]);
}

// The header_t right after the 8-byte fingerprint of a lockstep message, as
// skillbus.lockstep.peek_stamp reads it: false where Python would find no stamp, or a
// sender it would read differently (not ASCII: Python decodes it leniently).
bool read_stamp(const uint8_t* d, size_t n, int64_t& frame, int64_t& sim_time, std::string& sender, int32_t& seq) {
  if (n < 33) return false;
  frame = be64(d + 8);
  sim_time = be64(d + 16);
  const uint32_t len = static_cast<uint32_t>(be32(d + 24));
  const size_t start = 28;
  if (len < 1 || len > n || start + len + 4 > n) return false;
  sender.assign(reinterpret_cast<const char*>(d + start), len - 1);
  for (unsigned char ch : sender)
    if (ch == 0 || ch >= 0x80) return false;
  seq = be32(d + start + len);
  return !sender.empty() && seq >= 0 && frame >= 0 && sim_time >= 0;
}

using steady = std::chrono::steady_clock;

}  // namespace

QuietFrames::QuietFrames(QuietConfig config) : cfg_(std::move(config)), buffer_(kMaxDatagram) {
  if (cfg_.fd < 0) throw BusError("quiet frames: no socket");
  if (!cfg_.signing_key.empty()) sealer_ = std::make_unique<auth::Sealer>(cfg_.signing_key, cfg_.identity);
  lcm_ = lcm_create(cfg_.ack_url.c_str());
  if (!lcm_) throw BusError("quiet frames: cannot open LCM at " + cfg_.ack_url);
  Sha256 nothing;
  empty_frame_ = nothing.finish();
}

QuietFrames::~QuietFrames() {
  if (lcm_) lcm_destroy(lcm_);
}

bool QuietFrames::wait(QuietState& s, int timeout_ms, Datagram& out, std::vector<Handed>& handed) {
  s.acked = s.resends = 0;
  handed_.clear();
  // Every return hands Python the newest of what the core consumed; a return while a
  // frame is half collected hands it the frame (Python then waits with its own timeout
  // and names what is missing).
  struct Out {
    QuietFrames& q;
    std::vector<Handed>& handed;
    ~Out() {
      if (q.pending_) q.hand_all();
      q.hand_newest();
      handed = std::move(q.handed_);
      q.handed_.clear();
    }
  } hand_back{*this, handed};
  const auto deadline = steady::now() + std::chrono::milliseconds(std::max(0, timeout_ms));
  // poll, then read one datagram: two system calls a frame (reading until EAGAIN would be
  // three; datagrams rarely queue up here). The deadline holds even while datagrams keep
  // coming (a flood of forged clocks must not keep Python from its timeouts and signals).
  for (bool first = true;; first = false) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - steady::now()).count();
    if (left <= 0 && !first) return false;
    pollfd p{cfg_.fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, static_cast<int>(std::max<int64_t>(0, left)));
    if (ready < 0) {
      if (errno == EINTR) return false;  // a signal: Python's handlers run first
      throw std::system_error(errno, std::generic_category(), "polling the bus socket");
    }
    if (ready == 0) {
      if (left <= 0) return false;
      continue;  // (poll's own rounding: on to the deadline)
    }
    if (p.revents & POLLNVAL) throw std::system_error(EBADF, std::generic_category(), "polling the bus socket");
    sockaddr_in from{};
    socklen_t from_len = sizeof(from);
    const ssize_t n = ::recvfrom(cfg_.fd, buffer_.data(), buffer_.size(), MSG_DONTWAIT,
                                 reinterpret_cast<sockaddr*>(&from), &from_len);
    if (n < 0) {
      if (errno == EINTR) return false;
      if (errno == EAGAIN || errno == EWOULDBLOCK) continue;
      throw std::system_error(errno, std::generic_category(), "reading the bus socket");
    }
    const Verdict v = on_datagram(s, buffer_.data(), static_cast<size_t>(n));
    if (v == Verdict::Consumed) continue;
    if (v == Verdict::HandOver) {
      hand_all();
      return false;
    }
    if (pending_) hand_all();  // (Python takes the frame the core was collecting)
    out.data.assign(buffer_.begin(), buffer_.begin() + n);
    char ip[INET_ADDRSTRLEN] = "";
    ::inet_ntop(AF_INET, &from.sin_addr, ip, sizeof(ip));
    out.sender_ip = ip;
    out.sender_port = ntohs(from.sin_port);
    return true;
  }
}

QuietFrames::Verdict QuietFrames::on_datagram(QuietState& s, const uint8_t* d, size_t n) {
  if (n < 9 || std::memcmp(d, kShortMagic, 4) != 0) return Verdict::ForPython;  // fragments, junk
  const size_t room = std::min(n - 8, kMaxChannel + 1);
  const void* nul = std::memchr(d + 8, 0, room);
  if (!nul) return Verdict::ForPython;
  const size_t ch_len = static_cast<size_t>(static_cast<const uint8_t*>(nul) - (d + 8));
  const size_t head = 8 + ch_len + 1;
  if (ch_len == cfg_.clock_channel.size() && std::memcmp(d + 8, cfg_.clock_channel.data(), ch_len) == 0) {
    const Verdict v = on_clock(s, d + head, n - head);
    if (v == Verdict::ForPython && !held_.empty()) hand_all();  // Python takes the frame: its messages too
    return v;
  }
  if (latest_only_.empty()) return Verdict::ForPython;
  const std::string channel(reinterpret_cast<const char*>(d + 8), ch_len);
  if (!latest_only_.count(channel)) return Verdict::ForPython;
  return on_latest(s, channel, d + head, n - head);
}

// The happy path of LockstepParticipant._on_clock and _check_clock (py_skills/skillbus/
// lockstep.py); whatever else a clock is goes to Python, which records it. A clock is
// verified only when the core acts on it (acks a quiet frame, answers a resend): each
// message is verified once, by whoever handles it, with the bus's one replay window.
QuietFrames::Verdict QuietFrames::on_clock(QuietState& s, const uint8_t* d, size_t n) {
  size_t payload = n;
  if (cfg_.opener && !auth::unverified_payload_size(d, n, payload)) return Verdict::ForPython;  // unsigned
  skillbus_msgs::lockstep_clock_t c{};
  if (!decode_msg(d, payload, c)) return Verdict::ForPython;
  if (std::find(c.participants.begin(), c.participants.end(), cfg_.name) == c.participants.end())
    return Verdict::ForPython;
  if (s.master.empty() || c.header.sender != s.master || c.stop) return Verdict::ForPython;
  const int64_t frame = c.header.frame;
  size_t unused = 0;
  if (frame == s.last_acked && !s.last_ack.empty()) {  // the master resends: our ack was lost, or is late
    if (!verified(cfg_.clock_channel, d, n, unused)) return Verdict::Consumed;
    ++s.resends;
    send_ack(s.last_ack);
    return Verdict::Consumed;
  }
  if (pending_) return Verdict::ForPython;  // (a resend while collecting: Python sends its sign of life)
  if (frame != s.last_acked + 1 || c.header.sim_time_ns < s.last_sim_time) return Verdict::ForPython;
  if (frame > s.quiet_through_frame || c.header.sim_time_ns >= s.quiet_before_ns) return Verdict::ForPython;
  std::vector<Expected> expected;
  for (const auto& count : c.counts) {
    if (count.count < 0 || count.frame < 0 || count.frame > frame) return Verdict::ForPython;
    if (count.count > 0 && count.sender != cfg_.name && subscribed_.count(count.channel)) {
      if (!latest_only_.count(count.channel)) return Verdict::ForPython;  // a message for us: the frame has work
      expected.push_back({count.channel, count.sender, count.frame, count.count});
    }
  }
  size_t payload_size = n;
  if (!verified(cfg_.clock_channel, d, n, payload_size)) return Verdict::Consumed;
  if (!expected.empty()) {
    pending_ = Pending{frame, c.header.sim_time_ns, Bytes(d, d + payload_size), std::move(expected)};
    return complete_pending(s);
  }
  ack_quiet(s, frame, c.header.sim_time_ns);
  return Verdict::Consumed;
}

// A message on a latest-only channel: verified once, here, then placed.
QuietFrames::Verdict QuietFrames::on_latest(QuietState& s, const std::string& channel, const uint8_t* d, size_t n) {
  size_t payload_size = n;
  if (!verified(channel, d, n, payload_size)) return Verdict::Consumed;  // dropped and counted, as Python would
  return place(s, channel, d, payload_size);
}

// FrameInbox.add's rules (py_skills/skillbus/lockstep.py) for a verified payload.
QuietFrames::Verdict QuietFrames::place(QuietState& s, const std::string& channel, const uint8_t* d, size_t n) {
  int64_t frame = 0, sim_time = 0;
  int32_t seq = 0;
  std::string sender;
  if (!read_stamp(d, n, frame, sim_time, sender, seq) || held_count_ >= kMaxHeld) {
    handed_.push_back({Handed::Message, channel, Bytes(d, d + n)});  // Python records it, or copes
    return Verdict::HandOver;
  }
  if (sender == cfg_.name) return Verdict::Consumed;
  if (frame < s.last_acked) {
    ++stale_;
    return Verdict::Consumed;
  }
  auto& slot = held_[SlotKey{channel, sender, frame}];
  if (!slot.emplace(seq, Bytes(d, d + n)).second) {
    ++duplicates_;
    return Verdict::Consumed;
  }
  ++held_count_;
  if (pending_) return complete_pending(s);
  return Verdict::Consumed;
}

void QuietFrames::hold(const std::string& channel, const Bytes& payload, int64_t last_acked) {
  QuietState s;
  s.last_acked = last_acked;
  if (place(s, channel, payload.data(), payload.size()) == Verdict::HandOver) {
    // (Python's inbox took it: it has a stamp; only a flood ends here) back as it came
    handed_.pop_back();
    throw BusError("quiet frames: cannot hold more messages");
  }
}

// The pending clock's frame acked once every message it announced is held and its
// watches hold; the newest of each channel kept for Python, the slots before the frame
// dropped as stale (as the inbox's take does). A broken watch: Python takes the frame.
QuietFrames::Verdict QuietFrames::complete_pending(QuietState& s) {
  for (const auto& e : pending_->expected) {
    auto it = held_.find(SlotKey{e.channel, e.sender, e.frame});
    if (it == held_.end() || it->second.size() < static_cast<size_t>(e.count)) return Verdict::Consumed;
  }
  if (!watches_.empty() && !watches_hold()) return Verdict::HandOver;
  for (const auto& e : pending_->expected) {
    auto it = held_.find(SlotKey{e.channel, e.sender, e.frame});
    if (it == held_.end()) continue;  // (listed twice)
    for (auto& [seq, payload] : it->second) {
      Order order{e.frame, e.sender, seq};
      auto found = newest_.find(e.channel);
      if (found == newest_.end() || found->second.first < order) newest_[e.channel] = {order, std::move(payload)};
    }
    held_count_ -= it->second.size();
    held_.erase(it);
  }
  Pending p = std::move(*pending_);
  pending_.reset();
  ack_quiet(s, p.frame, p.sim_time_ns);
  for (auto it = held_.begin(); it != held_.end();) {
    if (std::get<2>(it->first) < p.frame) {
      stale_ += it->second.size();
      held_count_ -= it->second.size();
      it = held_.erase(it);
    } else {
      ++it;
    }
  }
  return Verdict::Consumed;
}

bool QuietFrames::watches_hold() const {
  for (const auto& [channel, watch] : watches_) {
    const Bytes* newest = nullptr;
    Order newest_order{};
    for (const auto& e : pending_->expected) {
      if (e.channel != channel) continue;
      auto it = held_.find(SlotKey{e.channel, e.sender, e.frame});
      for (const auto& [seq, payload] : it->second) {
        const Order order{e.frame, e.sender, seq};
        if (!newest || newest_order < order) newest = &payload, newest_order = order;
      }
    }
    if (newest && !finger_watch_holds(watch, newest->data(), newest->size())) return false;
  }
  return true;
}

void QuietFrames::hand_newest() {
  for (auto& [channel, entry] : newest_) handed_.push_back({Handed::Latest, channel, std::move(entry.second)});
  newest_.clear();
}

void QuietFrames::hand_all() {
  hand_newest();
  if (pending_) {
    handed_.push_back({Handed::Clock, cfg_.clock_channel, std::move(pending_->payload)});
    pending_.reset();
  }
  for (auto& [key, slot] : held_)
    for (auto& [seq, payload] : slot) handed_.push_back({Handed::Message, std::get<0>(key), std::move(payload)});
  held_.clear();
  held_count_ = 0;
}

std::vector<Handed> QuietFrames::release() {
  handed_.clear();
  hand_all();
  std::vector<Handed> out = std::move(handed_);
  handed_.clear();
  return out;
}

void QuietFrames::ack_quiet(QuietState& s, int64_t frame, int64_t sim_time_ns) {
  skillbus_msgs::lockstep_ack_t a{};
  a.header.frame = frame;
  a.header.sim_time_ns = sim_time_ns;
  a.header.sender = cfg_.name;
  a.header.seq = 0;
  a.num_counts = 0;
  std::copy(empty_frame_.begin(), empty_frame_.end(), a.digest);
  s.last_ack = encode_msg(a);
  s.last_acked = frame;
  s.last_sim_time = sim_time_ns;
  send_ack(s.last_ack);
  Sha256 h;
  h.update(s.running.data(), s.running.size());
  h.update(empty_frame_.data(), empty_frame_.size());
  s.running = h.finish();
  ++s.acked;
}

bool QuietFrames::verified(const std::string& channel, const uint8_t* d, size_t n, size_t& payload_size) {
  payload_size = n;
  if (!cfg_.opener) return true;  // an open bus
  std::string identity, why;
  auth::Reason reason{};
  std::lock_guard<std::mutex> lock(cfg_.opener->mutex);
  if (!cfg_.opener->opener.open(channel, d, n, payload_size, identity, reason, why)) {
    const std::string name = auth::reason_name(reason);
    ++rejected_[name];  // dropped and counted, as Python would
    ++verdicts_[{name, channel}];
    return false;
  }
  ++accepted_;
  ++verdicts_[{"ok", channel}];
  return true;
}

void QuietFrames::send_ack(const Bytes& ack) {
  int rc;
  if (sealer_) {
    const Bytes sealed = sealer_->seal(cfg_.ack_channel, ack.data(), ack.size());
    rc = lcm_publish(lcm_, cfg_.ack_channel.c_str(), sealed.data(), static_cast<unsigned>(sealed.size()));
  } else {
    rc = lcm_publish(lcm_, cfg_.ack_channel.c_str(), ack.data(), static_cast<unsigned>(ack.size()));
  }
  if (rc < 0) ++lost_sends_;  // lost as a datagram can be: the master resends the clock
}

}  // namespace skillbus::native
