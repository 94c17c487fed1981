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

bool QuietFrames::wait(QuietState& s, int timeout_ms, Datagram& out) {
  s.acked = s.resends = 0;
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
    if (on_datagram(s, buffer_.data(), static_cast<size_t>(n)) == Verdict::Consumed) continue;
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
  if (ch_len != cfg_.clock_channel.size() || std::memcmp(d + 8, cfg_.clock_channel.data(), ch_len) != 0)
    return Verdict::ForPython;
  const size_t head = 8 + ch_len + 1;
  return on_clock(s, d + head, n - head);
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
  if (frame == s.last_acked && !s.last_ack.empty()) {  // the master resends: our ack was lost, or is late
    if (!verified(d, n)) return Verdict::Consumed;
    ++s.resends;
    send_ack(s.last_ack);
    return Verdict::Consumed;
  }
  if (frame != s.last_acked + 1 || c.header.sim_time_ns < s.last_sim_time) return Verdict::ForPython;
  for (const auto& count : c.counts) {
    if (count.count < 0 || count.frame < 0 || count.frame > frame) return Verdict::ForPython;
    if (count.count > 0 && count.sender != cfg_.name && subscribed_.count(count.channel))
      return Verdict::ForPython;  // a message for us: the frame has work
  }
  if (!verified(d, n)) return Verdict::Consumed;
  skillbus_msgs::lockstep_ack_t a{};
  a.header.frame = frame;
  a.header.sim_time_ns = c.header.sim_time_ns;
  a.header.sender = cfg_.name;
  a.header.seq = 0;
  a.num_counts = 0;
  std::copy(empty_frame_.begin(), empty_frame_.end(), a.digest);
  s.last_ack = encode_msg(a);
  s.last_acked = frame;
  s.last_sim_time = c.header.sim_time_ns;
  send_ack(s.last_ack);
  Sha256 h;
  h.update(s.running.data(), s.running.size());
  h.update(empty_frame_.data(), empty_frame_.size());
  s.running = h.finish();
  ++s.acked;
  return Verdict::Consumed;
}

bool QuietFrames::verified(const uint8_t* d, size_t n) {
  if (!cfg_.opener) return true;  // an open bus
  size_t payload = 0;
  std::string identity, why;
  auth::Reason reason{};
  std::lock_guard<std::mutex> lock(cfg_.opener->mutex);
  if (!cfg_.opener->opener.open(cfg_.clock_channel, d, n, payload, identity, reason, why)) {
    ++rejected_[auth::reason_name(reason)];  // dropped and counted, as Python would
    return false;
  }
  ++accepted_;
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
