#include "skillbus/channel_filter.hpp"

#include <linux/filter.h>
#include <sys/socket.h>

#include <cerrno>
#include <cstdint>
#include <cstring>

namespace skillbus {

namespace {

// Offsets as a UDP socket's filter sees the datagram: from the UDP header (8 bytes).
constexpr uint32_t kUdpHeader = 8;
constexpr uint32_t kMagicAt = kUdpHeader;           // "LC02"
constexpr uint32_t kChannelAt = kUdpHeader + 8;     // after magic and sequence number
constexpr uint32_t kShortMagic = 0x4c433032;        // "LC02", as BPF loads it (big-endian)
constexpr uint32_t kKeep = 0xffffffffu;             // keep the whole datagram
constexpr uint32_t kDrop = 0;
constexpr size_t kMaxInstructions = BPF_MAXINSNS;
constexpr uint32_t kMaxChannel = 63;                // LCM_MAX_CHANNEL_NAME_LENGTH

sock_filter stmt(uint16_t code, uint32_t k) { return sock_filter{code, 0, 0, k}; }
sock_filter jump(uint16_t code, uint32_t k, uint8_t jt, uint8_t jf) { return sock_filter{code, jt, jf, k}; }

uint32_t be_word(const std::string& s, size_t at, size_t n) {
  uint32_t w = 0;
  for (size_t i = 0; i < n; ++i) w = w << 8 | static_cast<uint8_t>(s[at + i]);
  return w;
}

// One channel's test: the datagram is long enough, and its channel bytes, NUL included,
// are this name's. A mismatch jumps to the next channel's test; a match keeps the datagram.
std::vector<sock_filter> channel_test(const std::string& name) {
  std::string bytes = name;
  bytes.push_back('\0');
  std::vector<sock_filter> out;
  out.push_back(stmt(BPF_LD | BPF_W | BPF_LEN, 0));
  out.push_back(jump(BPF_JMP | BPF_JGE | BPF_K, kChannelAt + static_cast<uint32_t>(bytes.size()), 0, 0));
  for (size_t at = 0; at < bytes.size();) {
    const size_t n = bytes.size() - at >= 4 ? 4 : bytes.size() - at >= 2 ? 2 : 1;
    const uint16_t size = n == 4 ? BPF_W : n == 2 ? BPF_H : BPF_B;
    out.push_back(stmt(BPF_LD | size | BPF_ABS, kChannelAt + static_cast<uint32_t>(at)));
    out.push_back(jump(BPF_JMP | BPF_JEQ | BPF_K, be_word(bytes, at, n), 0, 0));
    at += n;
  }
  out.push_back(stmt(BPF_RET | BPF_K, kKeep));
  // Every conditional jump's false branch: past the keep, to the next channel's test.
  for (size_t i = 0; i + 1 < out.size(); ++i)
    if (BPF_CLASS(out[i].code) == BPF_JMP) out[i].jf = static_cast<uint8_t>(out.size() - 1 - i);
  return out;
}

}  // namespace

bool attach_channel_filter(int fd, const std::vector<std::string>& channels, std::string& why) {
  std::vector<sock_filter> prog = {
      stmt(BPF_LD | BPF_W | BPF_LEN, 0),
      jump(BPF_JMP | BPF_JGE | BPF_K, kChannelAt + 2, 1, 0),  // too short to name a channel:
      stmt(BPF_RET | BPF_K, kKeep),                          // the reader counts it
      stmt(BPF_LD | BPF_W | BPF_ABS, kMagicAt),
      jump(BPF_JMP | BPF_JEQ | BPF_K, kShortMagic, 1, 0),
      stmt(BPF_RET | BPF_K, kKeep),  // a fragment, or no LCM message: the reader's to judge
  };
  for (const auto& c : channels) {
    if (c.empty() || c.size() > kMaxChannel) continue;  // (no such subscription: the bus refuses them)
    const auto test = channel_test(c);
    prog.insert(prog.end(), test.begin(), test.end());
  }
  // No channel of ours. A well-formed short message of another channel is dropped; one
  // whose channel is malformed (empty, no NUL before the datagram ends or within LCM's 63
  // characters) is kept, so that the reader counts it as bad input as before.
  prog.push_back(stmt(BPF_LDX | BPF_W | BPF_LEN, 0));
  for (uint32_t i = 0; i <= kMaxChannel; ++i) {
    prog.push_back(stmt(BPF_LD | BPF_IMM, kChannelAt + i + 1));
    prog.push_back(jump(BPF_JMP | BPF_JGT | BPF_X, 0, 0, 1));  // the datagram ends before byte i
    prog.push_back(stmt(BPF_RET | BPF_K, kKeep));
    prog.push_back(stmt(BPF_LD | BPF_B | BPF_ABS, kChannelAt + i));
    prog.push_back(jump(BPF_JMP | BPF_JEQ | BPF_K, 0, 0, 1));
    prog.push_back(stmt(BPF_RET | BPF_K, i == 0 ? kKeep : kDrop));  // NUL: an empty channel, or the end of one
  }
  prog.push_back(stmt(BPF_RET | BPF_K, kKeep));  // longer than a channel can be
  if (prog.size() > kMaxInstructions) {
    why = "a filter for " + std::to_string(channels.size()) + " channels would take " + std::to_string(prog.size()) +
          " instructions (the kernel takes " + std::to_string(kMaxInstructions) + ")";
    detach_channel_filter(fd);
    return false;
  }
  sock_fprog fprog{static_cast<unsigned short>(prog.size()), prog.data()};
  if (::setsockopt(fd, SOL_SOCKET, SO_ATTACH_FILTER, &fprog, sizeof(fprog)) != 0) {
    why = std::string("the kernel refused the socket filter: ") + std::strerror(errno);
    detach_channel_filter(fd);
    return false;
  }
  return true;
}

void detach_channel_filter(int fd) {
  int unused = 0;
  ::setsockopt(fd, SOL_SOCKET, SO_DETACH_FILTER, &unused, sizeof(unused));  // (ENOENT: none attached)
}

}  // namespace skillbus
