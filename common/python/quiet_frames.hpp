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
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

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

  // Waits at most timeout_ms for a datagram this core does not consume, acking quiet
  // frames meanwhile. True with `out` filled: Python's to handle. False: the time is up,
  // or a signal came (Python runs its handlers, then waits again). A socket error throws
  // std::system_error.
  bool wait(QuietState& s, int timeout_ms, Datagram& out);

  // Clocks this core dropped, by reason, and accepted (cumulative): the bus adds them to
  // its own counts.
  const std::map<std::string, uint64_t>& rejected() const { return rejected_; }
  uint64_t accepted() const { return accepted_; }
  uint64_t lost_sends() const { return lost_sends_; }

 private:
  enum class Verdict { Consumed, ForPython };
  Verdict on_datagram(QuietState& s, const uint8_t* d, size_t n);
  Verdict on_clock(QuietState& s, const uint8_t* d, size_t n);
  bool verified(const uint8_t* d, size_t n);  // with the bus's opener; counted
  void send_ack(const Bytes& ack);

  QuietConfig cfg_;
  std::set<std::string> subscribed_;
  std::unique_ptr<auth::Sealer> sealer_;
  std::map<std::string, uint64_t> rejected_;
  uint64_t accepted_ = 0;
  lcm_t* lcm_ = nullptr;
  Digest empty_frame_{};  // SHA-256 of nothing: what a frame without publications hashes to
  uint64_t lost_sends_ = 0;
  Bytes buffer_;
};

}  // namespace skillbus::native
