// Receiving LCM's UDP multicast (udpm://) on the thread that dispatches.
//
// LCM's C library reads its socket on a thread of its own and wakes the dispatching
// thread through a pipe: two wake-ups, a pipe write and read and a lock per message. Under
// lockstep every participant takes one clock and the master one ack per participant each
// frame, so those hops were a large part of a frame (docs/transport.md). This reader
// takes datagrams from a non-blocking socket in LCM's wire format, so it and LCM's own
// receivers (lcm-spy, lcm-logger) interoperate both ways; publishing stays with LCM.
//
// Wire format (big-endian):
//   short message:      "LC02" | seqno u32 | channel NUL | payload
//   fragmented message: "LC03" | seqno u32 | size u32 | offset u32 | fragment u16 |
//                       fragments u16 | (fragment 0: channel NUL) | bytes
// The same design as py_skills/skillbus/udpm.py.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "skillbus/bus.hpp"

namespace skillbus {

// Turns datagrams into messages; what does not parse is counted and dropped. One
// incomplete fragmented message is kept per sender (LCM sends a message's fragments back
// to back under one lock, so a new sequence number means the previous message lost a
// fragment), at most kMaxPartials senders and kMaxPartialBytes bytes, the least recently
// heard dropped first.
class LcmReassembler {
 public:
  static constexpr size_t kMaxChannel = 63;             // LCM_MAX_CHANNEL_NAME_LENGTH
  static constexpr uint32_t kMaxPartialBytes = kMaxMessageBytes;  // as LCM
  static constexpr size_t kMaxPartials = 1000;           // as LCM

  // A complete message: its channel and bytes (valid until the next call).
  struct Message {
    std::string channel;
    const uint8_t* data = nullptr;
    size_t size = 0;
  };
  // True when `datagram` (from `sender`, any key naming it) completes a message.
  bool datagram(const uint8_t* d, size_t n, uint64_t sender, Message& out);

  long bad = 0;         // datagrams that do not parse, fragments that do not fit
  long incomplete = 0;  // fragmented messages given up (a fragment lost)

 private:
  struct Partial {
    uint32_t seqno = 0;
    uint16_t fragments = 0;
    std::string channel;
    std::vector<uint8_t> data;
    std::vector<bool> have;
    uint16_t count = 0;
    uint64_t heard = 0;
  };
  bool fragment(const uint8_t* d, size_t n, uint64_t sender, Message& out);
  void drop(uint64_t sender);

  std::map<uint64_t, Partial> partials_;  // by sender
  uint64_t partial_bytes_ = 0;
  uint64_t heard_ = 0;  // counts fragments: Partial::heard orders senders by when last heard
  std::vector<uint8_t> done_;  // the last completed fragmented message
};

// One multicast group and port, read without blocking (the socket set up as LCM sets up
// its own: bound to the group and port, address reuse, the group joined; a receive
// buffer of `receive_buffer` bytes when > 0).
class UdpmReceiver {
 public:
  UdpmReceiver(const std::string& group, int port, long receive_buffer);  // throws BusError
  ~UdpmReceiver();
  UdpmReceiver(const UdpmReceiver&) = delete;
  UdpmReceiver& operator=(const UdpmReceiver&) = delete;

  int fd() const { return fd_; }
  enum class Read { kNothing, kMessage, kNone };  // no datagram waiting / one completes / one completes none
  Read read(LcmReassembler::Message& out);
  const LcmReassembler& reassembler() const { return reassembler_; }

 private:
  int fd_ = -1;
  std::vector<uint8_t> buf_;
  LcmReassembler reassembler_;
};

// (group, port, recv_buf_size or 0) of a udpm:// URL; throws BusError for another URL.
struct UdpmAddress {
  std::string group;
  int port = 0;
  long receive_buffer = 0;
};
UdpmAddress udpm_address(const std::string& url);

}  // namespace skillbus
