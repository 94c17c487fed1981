// Pieces shared by the lockstep master and participants (docs/lockstep.md):
//  * Stamp: (frame, sim time, sender, seq), the header_t that every lockstep message
//    carries as its first field, read from raw bytes without knowing the message type;
//  * FrameOutbox: stamps, counts and hashes what one process publishes in a frame;
//  * FrameInbox: holds stamped messages until everything announced for a frame is
//    there, then hands them out in canonical order (frame, sender, seq).
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "skillbus/bus.hpp"
#include "skillbus/digest.hpp"
#include "skillbus/log.hpp"
#include "skillbus_msgs/channel_count_t.hpp"

namespace skillbus {

std::string clock_channel();  // SB_LOCKSTEP_CLOCK
std::string ack_channel();    // SB_LOCKSTEP_ACK
std::string join_channel();   // SB_LOCKSTEP_JOIN
std::string end_channel();    // SB_LOCKSTEP_END (a participant asks to end the session)

struct Stamp {
  int64_t frame = -1;
  int64_t sim_time_ns = 0;
  std::string sender;
  int32_t seq = 0;
};

// Reads the header_t that follows the 8-byte fingerprint. False if the bytes are too
// short or the header is implausible (empty sender, negative seq).
bool peek_stamp(const uint8_t* data, size_t size, Stamp& out);

struct StampedMessage {
  std::string channel;
  Stamp stamp;
  Bytes data;
};

using ChannelCount = skillbus_msgs::channel_count_t;

class FrameOutbox {
 public:
  FrameOutbox(Bus& bus, std::string sender) : bus_(bus), sender_(std::move(sender)) {}
  void begin_frame(int64_t frame, int64_t sim_time_ns);

  // Publishes `msg` stamped with this frame's header. The message is encoded as it is and
  // its header's bytes (the first field, right after the fingerprint) replaced: it is not
  // copied to be stamped (a task's progress, every tick, is a whole tree of strings).
  template <class T>
  void publish(const std::string& ch, const T& msg) {
    Bytes buf = encode_msg(msg);
    stamp(buf, static_cast<size_t>(msg.header._getEncodedSizeNoHash()));
    bus_.publish(ch, buf.data(), buf.size());
    ++counts_[ch];
    hash_.update_str(ch);
    hash_.update_bytes(buf.data(), buf.size());
  }

  // Replaces the `old_size` bytes of the header after the fingerprint with this frame's
  // stamp (frame, sim time, sender, the next seq).
  void stamp(Bytes& encoded, size_t old_size);

  std::vector<ChannelCount> counts() const;  // sorted by channel
  Digest finish_frame();                     // SHA-256 of this frame's publications
  int64_t frame() const { return frame_; }
  int64_t sim_time_ns() const { return sim_time_ns_; }
  const std::string& sender() const { return sender_; }

 private:
  Bus& bus_;
  std::string sender_;
  int64_t frame_ = -1, sim_time_ns_ = 0;
  int32_t seq_ = 0;
  std::map<std::string, int32_t> counts_;
  Sha256 hash_;
};

// The participant whose message a FrameInbox::missing() text names ("p1" above), or "".
// A participant that reports a lost message is not the one at fault: the sender (or the
// link from it) is, and the master's error names the sender.
std::string sender_of_missing(const std::string& missing_text);

class FrameInbox {
 public:
  FrameInbox(std::string self, BadInputCounter& bad) : self_(std::move(self)), bad_(bad) {}
  // Keeps a stamped message (own messages, stale frames and duplicates are dropped).
  void add(const std::string& ch, const uint8_t* data, size_t size);
  // "" when every expected message is held, else which are missing, e.g.
  // "channel SB_X from sender p1 in frame 12: got 0 of 1".
  std::string missing(const std::vector<ChannelCount>& expected) const;
  // Removes and returns the expected messages in canonical order (frame, sender, seq),
  // and forgets anything older than `frame`.
  std::vector<StampedMessage> take(const std::vector<ChannelCount>& expected, int64_t frame);
  long duplicates() const { return duplicates_; }
  long stale() const { return stale_; }

 private:
  using Key = std::tuple<std::string, std::string, int64_t>;  // channel, sender, frame
  std::string self_;
  BadInputCounter& bad_;
  std::map<Key, std::map<int32_t, StampedMessage>> held_;
  int64_t floor_ = -1;  // frames below this were handed out already
  long duplicates_ = 0, stale_ = 0;
};

// Filters announced counts down to what `subscribed` listens to, minus `self`.
std::vector<ChannelCount> expectations_for(const std::vector<ChannelCount>& announced,
                                           const std::set<std::string>& subscribed, const std::string& self);

struct RunResult {
  bool ok = true;
  std::string error;          // names the participant, or the channel and frame
  int64_t frames = 0;         // frames completed
  int64_t sim_time_ns = 0;
  double wall_seconds = 0;
  Digest digest{};            // master: of the whole session; participant: of its own output
  std::string digest_hex() const { return to_hex(digest); }
};

}  // namespace skillbus
