#include "udpm_receiver.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <regex>

#include "skillbus/bus.hpp"

namespace skillbus {

namespace {
constexpr uint32_t kShortMagic = 0x4c433032;  // "LC02"
constexpr uint32_t kLongMagic = 0x4c433033;   // "LC03"
constexpr size_t kLongHeader = 20;

uint32_t be32(const uint8_t* p) { return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3]; }
uint16_t be16(const uint8_t* p) { return uint16_t(p[0] << 8 | p[1]); }

// The channel: NUL-terminated at `p`, at most kMaxChannel bytes, within `end`. Its length,
// or -1.
long channel_length(const uint8_t* p, const uint8_t* end) {
  const size_t room = std::min<size_t>(static_cast<size_t>(end - p), LcmReassembler::kMaxChannel + 1);
  const void* nul = std::memchr(p, 0, room);
  return nul ? static_cast<const uint8_t*>(nul) - p : -1;
}
}  // namespace

bool LcmReassembler::datagram(const uint8_t* d, size_t n, uint64_t sender, Message& out) {
  if (n >= 8 && be32(d) == kShortMagic) {
    const long len = channel_length(d + 8, d + n);
    if (len <= 0) {
      ++bad;
      return false;
    }
    out.channel.assign(reinterpret_cast<const char*>(d + 8), static_cast<size_t>(len));
    out.data = d + 8 + len + 1;
    out.size = n - 8 - static_cast<size_t>(len) - 1;
    return true;
  }
  if (n >= kLongHeader && be32(d) == kLongMagic) return fragment(d, n, sender, out);
  ++bad;
  return false;
}

bool LcmReassembler::fragment(const uint8_t* d, size_t n, uint64_t sender, Message& out) {
  const uint32_t seqno = be32(d + 4), size = be32(d + 8), offset = be32(d + 12);
  const uint16_t number = be16(d + 16), fragments = be16(d + 18);
  if (size > kMaxPartialBytes || fragments == 0 || number >= fragments) {
    ++bad;
    return false;
  }
  auto it = partials_.find(sender);
  if (it != partials_.end() &&
      (it->second.seqno != seqno || it->second.data.size() != size || it->second.fragments != fragments)) {
    drop(sender);  // the sender's previous message lost a fragment
    ++incomplete;
    it = partials_.end();
  }
  const uint8_t* body = d + kLongHeader;
  std::string channel;
  if (number == 0) {
    const long len = channel_length(body, d + n);
    if (len <= 0) {
      ++bad;
      return false;
    }
    channel.assign(reinterpret_cast<const char*>(body), static_cast<size_t>(len));
    body += len + 1;
  }
  const size_t chunk = static_cast<size_t>(d + n - body);
  if (uint64_t(offset) + chunk > size) {
    ++bad;
    if (it != partials_.end()) drop(sender);
    return false;
  }
  if (it == partials_.end()) {
    while (!partials_.empty() && (partials_.size() >= kMaxPartials || partial_bytes_ + size > kMaxPartialBytes)) {
      auto oldest = partials_.begin();
      for (auto j = partials_.begin(); j != partials_.end(); ++j)
        if (j->second.heard < oldest->second.heard) oldest = j;
      drop(oldest->first);
      ++incomplete;
    }
    Partial p;
    p.seqno = seqno;
    p.fragments = fragments;
    p.data.resize(size);
    p.have.assign(fragments, false);
    partial_bytes_ += size;
    it = partials_.emplace(sender, std::move(p)).first;
  }
  Partial& p = it->second;
  p.heard = ++heard_;
  if (p.have[number]) return false;  // a duplicate
  if (chunk) std::memcpy(p.data.data() + offset, body, chunk);
  p.have[number] = true;
  if (number == 0) p.channel = std::move(channel);
  if (++p.count < p.fragments) return false;
  done_ = std::move(p.data);
  out.channel = std::move(p.channel);
  drop(sender);
  out.data = done_.data();
  out.size = done_.size();
  return true;
}

void LcmReassembler::drop(uint64_t sender) {
  auto it = partials_.find(sender);
  if (it == partials_.end()) return;
  partial_bytes_ -= it->second.data.size();
  partials_.erase(it);
}

UdpmAddress udpm_address(const std::string& url) {
  static const std::regex udpm(R"(^udpm://([^:/?]*)(?::(\d+))?(\?.*)?$)");
  static const std::regex buffer(R"([?&]recv_buf_size=(\d+))");
  std::smatch m;
  if (!std::regex_match(url, m, udpm)) throw BusError("bus URL '" + url + "': not a udpm:// URL");
  UdpmAddress a;
  a.group = m[1].str().empty() ? "239.255.76.67" : m[1].str();
  a.port = m[2].matched ? std::stoi(m[2].str()) : 7667;
  const std::string query = m[3].str();
  std::smatch b;
  if (std::regex_search(query, b, buffer)) a.receive_buffer = std::stol(b[1].str());
  return a;
}

UdpmReceiver::UdpmReceiver(const std::string& group, int port, long receive_buffer) : buf_(65536) {
  auto fail = [&](const std::string& what) {
    const std::string why = std::strerror(errno);
    if (fd_ >= 0) ::close(fd_);
    throw BusError("cannot receive on udpm://" + group + ":" + std::to_string(port) + ": " + what + ": " + why +
                   " (for udpm:// the host needs a multicast route, e.g. `ip route add 224.0.0.0/4 dev lo`)");
  };
  in_addr group_addr{};
  if (::inet_aton(group.c_str(), &group_addr) == 0) {
    errno = EINVAL;
    fail("the group is no IPv4 address");
  }
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, IPPROTO_UDP);
  if (fd_ < 0) fail("socket");
  const int one = 1;
  if (::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) < 0) fail("SO_REUSEADDR");
  if (receive_buffer > 0) {
    const int size = static_cast<int>(std::min<long>(receive_buffer, INT32_MAX / 2));
    if (::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &size, sizeof size) < 0) fail("SO_RCVBUF");
  }
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr = group_addr;
  addr.sin_port = htons(static_cast<uint16_t>(port));
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) < 0) fail("bind");
  ip_mreq mreq{};
  mreq.imr_multiaddr = group_addr;
  mreq.imr_interface.s_addr = htonl(INADDR_ANY);
  if (::setsockopt(fd_, IPPROTO_IP, IP_ADD_MEMBERSHIP, &mreq, sizeof mreq) < 0) fail("joining the group");
}

UdpmReceiver::~UdpmReceiver() {
  if (fd_ >= 0) ::close(fd_);
}

UdpmReceiver::Read UdpmReceiver::read(LcmReassembler::Message& out) {
  sockaddr_in from{};
  socklen_t from_len = sizeof from;
  const ssize_t n = ::recvfrom(fd_, buf_.data(), buf_.size(), 0, reinterpret_cast<sockaddr*>(&from), &from_len);
  if (n < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return Read::kNothing;
    throw BusError(std::string("receiving on the bus failed: ") + std::strerror(errno));
  }
  const uint64_t sender = uint64_t(from.sin_addr.s_addr) << 16 | from.sin_port;
  return reassembler_.datagram(buf_.data(), static_cast<size_t>(n), sender, out) ? Read::kMessage : Read::kNone;
}

}  // namespace skillbus
