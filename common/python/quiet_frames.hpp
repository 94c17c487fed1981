// Quiet lockstep frames of a Python participant, acknowledged without the interpreter.
//
// A lockstep participant with nothing to do in a frame (no frame callback, no message
// it subscribed to announced by the clock, nothing held for the frame) still has to take
// the clock and send a signed ack. In Python that costs the interpreter's wake-up, the
// clock's verification and decoding and the ack's encoding and signature: several times
// what the same frame costs a C++ participant (docs/benchmarks.md). QuietFrames takes
// over the participant's socket while it waits for a clock: it reads the datagrams
// itself, acks every quiet frame as py_skills/skillbus/lockstep.py would (the same bytes,
// the same running digest), and returns to Python at the first datagram that is anything
// else: another channel's message, a clock with work in it, a stop, anything odd. Python
// then handles that datagram on its own path, so every rule stays written once there:
// the core only repeats the happy path.
//
// Latest-only channels: a participant whose handler for a channel only keeps the newest
// message (a robot's state, published every frame) marks it so. A frame whose only
// announced messages are on such channels is quiet too: the core waits for them as
// Python's inbox would (every announced message, verified), keeps the newest per
// channel, acks the frame, and hands the newest to Python when it next wakes. A
// participant with a frame callback says how far its next frames would do nothing (the
// horizon: a frame number and a sim time); frames past it go to Python. A participant that
// reads a latest-only state for something it watches (the simulated gripper holding an
// object) may give bounds the state must keep (finger_watch.hpp): a frame that breaks
// them goes to Python.
//
// What the core verified is never handed back as a datagram (a second check would call
// it a replay): it goes back as a payload, with the clock it was collecting, whenever
// Python takes over a frame (a clock the core does not ack, a message it cannot place,
// the wait's end while a frame is half collected, release()).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "finger_watch.hpp"
#include "skillbus/auth.hpp"
#include "skillbus/bus.hpp"
#include "skillbus/digest.hpp"
#include "shared_opener.hpp"

typedef struct _lcm_t lcm_t;

namespace skillbus::native {

struct QuietConfig {
  int fd = -1;                   // the participant's lane-0 udpm socket (non-blocking)
  std::string clock_channel;     // SB_LOCKSTEP_CLOCK (with the namespace)
  std::string ack_channel;       // SB_LOCKSTEP_ACK (with the namespace)
  std::string ack_url;           // the LCM URL acks go out on (lane 1)
  std::string name;              // the participant
  std::shared_ptr<SharedOpener> opener;  // the bus's; null: an open bus (nothing verified)
  auth::Key signing_key;         // empty: an open bus (nothing signed)
  std::string identity;          // the bus identity acks are signed with
};

// What Python and the core hand each other around a wait: Python's participant state.
struct QuietState {
  std::string master;      // the master whose clock the participant follows
  int64_t last_acked = -1;
  int64_t last_sim_time = 0;
  Bytes last_ack;          // the last ack's bytes (unsigned), for clock resends
  Digest running{};        // the running digest of the participant's frames
  int64_t acked = 0;       // out: quiet frames acked by this wait
  int64_t resends = 0;     // out: clock resends answered (the master is alive)
  // The horizon: frames after quiet_through_frame, or at or after quiet_before_ns of sim
  // time, go to Python (its frame callback has work then). No callback: no horizon.
  int64_t quiet_through_frame = INT64_MAX;
  int64_t quiet_before_ns = INT64_MAX;
};

// A verified payload handed back to Python.
struct Handed {
  enum Kind { Latest = 0, Clock = 1, Message = 2 };
  Kind kind;            // Latest: the newest of a channel's messages in frames the core acked
                        // (for the handler); Clock: the clock of a frame the core was
                        // collecting; Message: held for a frame Python takes (for its inbox)
  std::string channel;
  Bytes payload;
};

struct Datagram {
  Bytes data;
  std::string sender_ip;
  int sender_port = 0;
};

class QuietFrames {
 public:
  explicit QuietFrames(QuietConfig config);  // throws BusError
  ~QuietFrames();
  QuietFrames(const QuietFrames&) = delete;
  QuietFrames& operator=(const QuietFrames&) = delete;

  void set_subscribed(std::set<std::string> channels) { subscribed_ = std::move(channels); }
  // Subscribed channels whose handler only keeps the newest message.
  void set_latest_only(std::set<std::string> channels) { latest_only_ = std::move(channels); }
  // A latest-only channel of sim_state_t whose newest message in a frame must keep the
  // fingers within `w` for the frame to be quiet (finger_watch.hpp); set before each wait.
  void set_finger_watch(const std::string& channel, const FingerWatch& w) { watches_[channel] = w; }
  void clear_watches() { watches_.clear(); }

  // Waits at most timeout_ms for a datagram this core does not consume, acking quiet
  // frames meanwhile. True with `out` filled: Python's to handle. False: the time is up,
  // a signal came (Python runs its handlers, then waits again), or the core hands Python
  // a frame (`handed`, which every return may fill: Python handles it first). A socket
  // error throws std::system_error.
  bool wait(QuietState& s, int timeout_ms, Datagram& out, std::vector<Handed>& handed);

  // Messages Python verified and holds for coming frames, on latest-only channels (its
  // inbox's), given to the core before a wait. `last_acked` is Python's floor.
  void hold(const std::string& channel, const Bytes& payload, int64_t last_acked);

  // Everything the core holds, back to Python (which stops using the core).
  std::vector<Handed> release();

  uint64_t stale() const { return stale_; }            // latest-only messages of frames already done
  uint64_t duplicates() const { return duplicates_; }  // ... with a (sender, frame, seq) held already
  // Messages verified ("ok") and dropped, by reason and channel (cumulative).
  const std::map<std::pair<std::string, std::string>, uint64_t>& verdicts() const { return verdicts_; }

  // Clocks this core dropped, by reason, and accepted (cumulative): the bus adds them to
  // its own counts.
  const std::map<std::string, uint64_t>& rejected() const { return rejected_; }
  uint64_t accepted() const { return accepted_; }
  uint64_t lost_sends() const { return lost_sends_; }

 private:
  // Consumed: done with it. ForPython: the raw datagram is Python's. HandOver: Python
  // takes over the frame (what the core verified is in handed_).
  enum class Verdict { Consumed, ForPython, HandOver };
  Verdict on_datagram(QuietState& s, const uint8_t* d, size_t n);
  Verdict on_clock(QuietState& s, const uint8_t* d, size_t n);
  Verdict on_latest(QuietState& s, const std::string& channel, const uint8_t* d, size_t n);
  Verdict place(QuietState& s, const std::string& channel, const uint8_t* payload, size_t n);
  // With the bus's opener; counted. `payload_size` out: the message without its seal.
  bool verified(const std::string& channel, const uint8_t* d, size_t n, size_t& payload_size);
  void ack_quiet(QuietState& s, int64_t frame, int64_t sim_time_ns);
  Verdict complete_pending(QuietState& s);
  bool watches_hold() const;  // the pending frame's newest messages keep within their watches
  void hand_newest();
  void hand_all();
  void send_ack(const Bytes& ack);

  // A clock whose announced messages (all on latest-only channels) are being collected.
  struct Expected {
    std::string channel, sender;
    int64_t frame;
    int32_t count;
  };
  struct Pending {
    int64_t frame, sim_time_ns;
    Bytes payload;  // the clock, verified
    std::vector<Expected> expected;
  };
  using SlotKey = std::tuple<std::string, std::string, int64_t>;  // channel, sender, frame
  using Order = std::tuple<int64_t, std::string, int32_t>;        // frame, sender, seq

  QuietConfig cfg_;
  std::set<std::string> subscribed_, latest_only_;
  std::map<std::string, FingerWatch> watches_;
  std::optional<Pending> pending_;
  std::map<SlotKey, std::map<int32_t, Bytes>> held_;           // verified, for coming frames
  size_t held_count_ = 0;
  std::map<std::string, std::pair<Order, Bytes>> newest_;      // consumed, not yet handed
  std::vector<Handed> handed_;                                 // the current wait's hand-over
  uint64_t stale_ = 0, duplicates_ = 0;
  std::map<std::pair<std::string, std::string>, uint64_t> verdicts_;
  std::unique_ptr<auth::Sealer> sealer_;
  std::map<std::string, uint64_t> rejected_;
  uint64_t accepted_ = 0;
  lcm_t* lcm_ = nullptr;
  Digest empty_frame_{};  // SHA-256 of nothing: what a frame without publications hashes to
  uint64_t lost_sends_ = 0;
  Bytes buffer_;
};

}  // namespace skillbus::native
