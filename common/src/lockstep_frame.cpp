#include "skillbus/lockstep_frame.hpp"

#include <algorithm>

#include "skillbus_msgs/header_t.hpp"

namespace skillbus {

std::string clock_channel() { return channel("SB_LOCKSTEP_CLOCK"); }
std::string ack_channel() { return channel("SB_LOCKSTEP_ACK"); }
std::string join_channel() { return channel("SB_LOCKSTEP_JOIN"); }
std::string end_channel() { return channel("SB_LOCKSTEP_END"); }

bool peek_stamp(const uint8_t* data, size_t size, Stamp& out) {
  if (size < 8 + 8 + 8 + 4 + 1 + 4 || size > static_cast<size_t>(INT32_MAX)) return false;
  skillbus_msgs::header_t h;
  try {
    if (h._decodeNoHash(data, 8, static_cast<int>(size) - 8) < 0) return false;
  } catch (const std::exception&) {  // corrupt string length (see decode_msg)
    return false;
  }
  if (h.sender.empty() || h.seq < 0 || h.frame < 0) return false;
  out.frame = h.frame;
  out.sim_time_ns = h.sim_time_ns;
  out.sender = std::move(h.sender);
  out.seq = h.seq;
  return true;
}

// ---------------------------------------------------------------- outbox

void FrameOutbox::begin_frame(int64_t frame, int64_t sim_time_ns) {
  frame_ = frame;
  sim_time_ns_ = sim_time_ns;
  seq_ = 0;
  counts_.clear();
  hash_.finish();  // reset
}

void FrameOutbox::stamp(Bytes& encoded, size_t old_size) {
  constexpr size_t kFingerprint = 8;
  skillbus_msgs::header_t h;
  h.frame = frame_;
  h.sim_time_ns = sim_time_ns_;
  h.sender = sender_;
  h.seq = seq_++;
  const size_t size = static_cast<size_t>(h._getEncodedSizeNoHash());
  if (encoded.size() < kFingerprint + old_size) throw BusError("FrameOutbox: a message shorter than its header");
  if (size > old_size)
    encoded.insert(encoded.begin() + kFingerprint, size - old_size, 0);
  else if (size < old_size)
    encoded.erase(encoded.begin() + kFingerprint, encoded.begin() + static_cast<std::ptrdiff_t>(kFingerprint + old_size - size));
  h._encodeNoHash(encoded.data(), static_cast<int>(kFingerprint), static_cast<int>(size));
}

std::vector<ChannelCount> FrameOutbox::counts() const {
  std::vector<ChannelCount> out;
  for (const auto& [ch, n] : counts_) {
    ChannelCount c;
    c.sender = sender_;
    c.channel = ch;
    c.frame = frame_;
    c.count = n;
    out.push_back(c);
  }
  return out;
}

Digest FrameOutbox::finish_frame() { return hash_.finish(); }

// ---------------------------------------------------------------- inbox

void FrameInbox::add(const std::string& ch, const uint8_t* data, size_t size) {
  Stamp s;
  if (!peek_stamp(data, size, s)) {
    bad_.record(ch, "no lockstep header (frame, sender, seq)", size);
    return;
  }
  if (s.sender == self_) return;
  if (s.frame < floor_) {
    ++stale_;
    return;
  }
  auto& slot = held_[Key{ch, s.sender, s.frame}];
  if (slot.count(s.seq)) {
    ++duplicates_;
    return;
  }
  const int32_t seq = s.seq;
  slot.emplace(seq, StampedMessage{ch, std::move(s), Bytes(data, data + size)});
}

std::string FrameInbox::missing(const std::vector<ChannelCount>& expected) const {
  for (const auto& e : expected) {
    auto it = held_.find(Key{e.channel, e.sender, e.frame});
    const int32_t got = it == held_.end() ? 0 : static_cast<int32_t>(it->second.size());
    if (got < e.count)
      return "channel " + e.channel + " from sender " + e.sender + " in frame " + std::to_string(e.frame) +
             ": got " + std::to_string(got) + " of " + std::to_string(e.count);
  }
  return "";
}

std::string sender_of_missing(const std::string& missing_text) {
  static const std::string from = " from sender ", in = " in frame ";
  const auto a = missing_text.find(from);
  if (a == std::string::npos) return "";
  const auto b = missing_text.find(in, a + from.size());
  if (b == std::string::npos) return "";
  return missing_text.substr(a + from.size(), b - a - from.size());
}

std::vector<StampedMessage> FrameInbox::take(const std::vector<ChannelCount>& expected, int64_t frame) {
  std::vector<StampedMessage> out;
  for (const auto& e : expected) {
    auto it = held_.find(Key{e.channel, e.sender, e.frame});
    if (it == held_.end()) continue;
    for (auto& [seq, m] : it->second) out.push_back(std::move(m));
    held_.erase(it);
  }
  std::sort(out.begin(), out.end(), [](const StampedMessage& a, const StampedMessage& b) {
    return std::tie(a.stamp.frame, a.stamp.sender, a.stamp.seq) < std::tie(b.stamp.frame, b.stamp.sender, b.stamp.seq);
  });
  floor_ = std::max(floor_, frame);
  for (auto it = held_.begin(); it != held_.end();) {
    if (std::get<2>(it->first) < floor_) {
      stale_ += static_cast<long>(it->second.size());
      it = held_.erase(it);
    } else {
      ++it;
    }
  }
  return out;
}

std::vector<ChannelCount> expectations_for(const std::vector<ChannelCount>& announced,
                                           const std::set<std::string>& subscribed, const std::string& self) {
  std::vector<ChannelCount> out;
  for (const auto& c : announced)
    if (c.sender != self && c.count > 0 && subscribed.count(c.channel)) out.push_back(c);
  return out;
}

}  // namespace skillbus
