// The bus: publish bytes on a channel, subscribe a handler, dispatch with a timeout.
//
// Every skillbus process talks through this interface, never through LCM directly, so
// that the transport is picked by a URL at start-up:
//   udpm://239.255.76.67:7667?ttl=0   LCM over UDP multicast (the default; LCM publishes,
//                                     the bus reads the socket itself: docs/transport.md)
//   memq://                           LCM in-process queue (unit tests)
//   dds://DOMAIN                      Cyclone DDS (loopback only unless told; docs/transport.md)
// Dispatch is single-threaded: handlers run inside handle(), on the caller's thread.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace skillbus {

using Bytes = std::vector<uint8_t>;

// A handler sees the channel a message arrived on and its raw bytes. The bytes are
// valid only for the duration of the call.
using Handler = std::function<void(const std::string& channel, const uint8_t* data, size_t size)>;

constexpr const char* kDefaultBusUrl = "udpm://239.255.76.67:7667?ttl=0";

class BusError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Bus {
 public:
  virtual ~Bus() = default;
  virtual void publish(const std::string& channel, const void* data, size_t size) = 0;
  // `channel` is an exact name. queue_capacity bounds how many undelivered messages are
  // kept for this subscription where LCM queues them (memq://; LCM's default of 30
  // silently drops bursts, so ours is far larger); on udpm:// the socket's receive
  // buffer is the queue.
  virtual int subscribe(const std::string& channel, Handler handler, int queue_capacity = 10000) = 0;
  virtual void unsubscribe(int subscription_id) = 0;
  // Dispatches pending messages, waiting at most `timeout` for the first one.
  // Returns true if at least one message was handled.
  virtual bool handle(std::chrono::milliseconds timeout) = 0;
  virtual std::string url() const = 0;
  // The last moment this bus had nothing left to hand out: every message that had
  // arrived by then was dispatched. A wall-clock liveness check measures a sender's
  // silence up to here, not up to now: a process that was not scheduled for seconds (a
  // loaded machine, a stopped debugger) has not heard senders that kept sending, and
  // must not call them dead. A bus that cannot tell says now.
  virtual std::chrono::steady_clock::time_point caught_up_at() const { return std::chrono::steady_clock::now(); }
};

// The URL from the argument, else $SKILLBUS_BUS_URL, else kDefaultBusUrl.
std::string resolve_bus_url(const std::string& url = "");

// udpm:// only: throws BusError (saying what to do) when the URL's multicast group would
// be joined on a network interface other than loopback, unless that interface is
// $SKILLBUS_NETWORK. open_bus() calls it: local by default (docs/security.md).
void check_multicast_interface(const std::string& url);

// Opens the backend that the URL names; throws BusError naming the URL when it cannot.
std::unique_ptr<Bus> open_bus(const std::string& url = "");

// Channel names (docs/transport.md, "Several robots"). Several robots share one bus:
// a robot's own channels (its arm, camera, fingers, skill manager, skill processes,
// motion service, CAN sync: robot_scoped()) are "<robot>/<name>" for the process's
// robot, while the world model, the lockstep, the physics server's control and the log
// are shared. Everything goes behind $SKILLBUS_NAMESPACE (empty by default: a whole
// system apart on one bus).
//   channel("SB_WM_REQ")          -> "<ns>SB_WM_REQ"
//   channel("SB_ROBOT_ARM_STATE") -> "<ns>r2/SB_ROBOT_ARM_STATE" in a process of robot r2
// Both throw std::invalid_argument for a name longer than kMaxChannel, naming the part
// that made it long (a skill process's name, the robot's, $SKILLBUS_NAMESPACE).
std::string channel(const std::string& name);
// The same for an explicit robot ("" for none): the physics server serves every robot.
std::string robot_channel(const std::string& name, const std::string& robot);
// LCM ends channel names at 63 bytes (LCM_MAX_CHANNEL_NAME_LENGTH). DDS carries longer
// ones, but one name must work on both, and every backend refuses a longer name with a
// BusError: on LCM it would subscribe and never hear a message.
constexpr size_t kMaxChannel = 63;
// Why `name` cannot be a channel, "" when it can; the backends' check, throwing BusError.
std::string channel_too_long(const std::string& name);
// Why `name` cannot be a DDS topic (Cyclone 0.10: letters, digits, _ and /, not starting
// with a digit), "" when it can; channel() refuses such names on either transport.
std::string channel_bad_characters(const std::string& name);
void refuse_long_channel(const std::string& name);
// The largest message a receiver reassembles from LCM's fragments (as LCM): a larger one
// would be sent and dropped by every receiver, so every backend refuses it with a
// BusError naming the channel and the size (on DDS too: one limit, both transports).
// Replies of any size go in chunks (rpc.hpp); other large data goes in parts.
constexpr size_t kMaxMessageBytes = size_t{1} << 24;  // 16 MiB
void refuse_oversized(const std::string& channel, size_t size);
bool robot_scoped(const std::string& name);
// The process's robot: set_robot() (a program's --robot), else $SKILLBUS_ROBOT, else "".
std::string current_robot();
// Throws std::invalid_argument unless valid_robot_name(robot) or robot is "".
void set_robot(const std::string& robot);
// A letter, then letters, digits or _: it becomes part of channel and DDS topic names.
bool valid_robot_name(const std::string& robot);

// Typed helpers over the generated LCM bindings.
template <class T>
void publish_msg(Bus& bus, const std::string& ch, const T& msg) {
  Bytes buf(static_cast<size_t>(msg.getEncodedSize()));
  if (msg.encode(buf.data(), 0, static_cast<int>(buf.size())) < 0)
    throw BusError("cannot encode message for channel " + ch);
  bus.publish(ch, buf.data(), buf.size());
}

template <class T>
Bytes encode_msg(const T& msg) {
  Bytes buf(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

// Decodes `size` bytes as T; returns false (leaving `out` unspecified) on a wrong type
// fingerprint or truncated bytes. Never throws on bad input.
// (LCM's generated C++ throws std::length_error on some corrupt string lengths; that is
// caught here, which is why every decode goes through this function.)
template <class T>
bool decode_msg(const uint8_t* data, size_t size, T& out) {
  if (size > static_cast<size_t>(INT32_MAX)) return false;
  try {
    return out.decode(data, 0, static_cast<int>(size)) == static_cast<int>(size);
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace skillbus
