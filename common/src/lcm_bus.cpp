#include "lcm_bus.hpp"

#include <poll.h>

#include <cerrno>
#include <cstdlib>
#include <algorithm>
#include <cstring>
#include <fstream>
#include <regex>

#include "channel_names.hpp"
#include "skillbus/channel_filter.hpp"
#include "skillbus/log.hpp"

namespace skillbus {

using detail::ends_with;

int lcm_lane_of(const std::string& channel) {
  return ends_with(channel, "_ACK") || ends_with(channel, "_JOIN") ? 1 : 0;
}

std::string lcm_lane1_url(const std::string& url) {
  static const std::regex udpm(R"(^udpm://([^:/?]*)(?::(\d+))?(\?.*)?$)");
  std::smatch m;
  if (!std::regex_match(url, m, udpm)) return "";
  // Lane 1 is port+1: a port that leaves no room for it is refused here, naming why (LCM
  // would refuse lane 1's URL only when the first ack is sent; a receiver would wrap it).
  const std::string p = m[2].matched ? m[2].str() : "7667";
  const int port = p.size() <= 5 ? std::stoi(p) : 0;
  if (port < 1 || port > 65534)
    throw BusError("bus URL '" + url + "': port " + p + " (1 to 65534: the second lane, for acks and joins, is port+1)");
  const std::string addr = m[1].str().empty() ? "239.255.76.67" : m[1].str();
  return "udpm://" + addr + ":" + std::to_string(port + 1) + m[3].str();
}

std::string lcm_url_with_receive_buffer(const std::string& url, long rmem_max) {
  if (url.rfind("udpm://", 0) != 0 || url.find("recv_buf_size=") != std::string::npos) return url;
  const long size = rmem_max > 0 ? std::min(kLcmReceiveBuffer, rmem_max) : kLcmReceiveBuffer;
  return url + (url.find('?') == std::string::npos ? "?" : "&") + "recv_buf_size=" + std::to_string(size);
}

long kernel_receive_buffer_cap() {
  std::ifstream f("/proc/sys/net/core/rmem_max");
  long v = -1;
  return (f >> v) ? v : -1;
}

namespace {

std::string receive_buffer_url(const std::string& url) {
  if (url.rfind("udpm://", 0) != 0 || url.find("recv_buf_size=") != std::string::npos) return url;
  const long cap = kernel_receive_buffer_cap();
  static bool warned = false;
  if (cap > 0 && cap < kLcmReceiveBuffer && !warned) {
    warned = true;
    SB_WARN("bus", "the kernel caps a socket's UDP receive buffer at " << cap << " bytes (net.core.rmem_max), under the "
                   << kLcmReceiveBuffer << " skillbus asks for: a large reply or a burst can be lost; raise it with "
                   << "`sudo sysctl -w net.core.rmem_max=" << kLcmReceiveBuffer << "`");
  }
  return lcm_url_with_receive_buffer(url, cap);
}

}  // namespace

LcmBus::LcmBus(const std::string& url)
    : url_(url),
      lane_urls_{receive_buffer_url(url), receive_buffer_url(lcm_lane1_url(url))},
      // ($SKILLBUS_LCM_RECEIVE_THREAD set: LCM's own receive thread, as before; docs/transport.md)
      direct_(url.rfind("udpm://", 0) == 0 && !std::getenv("SKILLBUS_LCM_RECEIVE_THREAD")) {
  lane(0);  // fail early, with a clear message, on a bad URL or a missing multicast route
}

LcmBus::~LcmBus() {
  for (auto& [id, sub] : subs_)
    if (sub->lcm_sub) lcm_unsubscribe(lanes_[sub->lane], sub->lcm_sub);
  for (lcm_t* l : lanes_)
    if (l) lcm_destroy(l);
}

lcm_t* LcmBus::lane(int i) {
  if (lane_urls_[i].empty()) i = 0;  // single-lane URL
  if (!lanes_[i]) {
    lanes_[i] = lcm_create(lane_urls_[i].c_str());
    if (!lanes_[i])
      throw BusError("cannot open LCM at '" + lane_urls_[i] +
                     "' (for udpm:// the host needs a multicast route, e.g. `ip route add 224.0.0.0/4 dev lo`)");
  }
  return lanes_[i];
}

void LcmBus::publish(const std::string& channel, const void* data, size_t size) {
  refuse_long_channel(channel);
  refuse_oversized(channel, size);
  lcm_t* l = lane(lcm_lane_of(channel));
  errno = 0;
  if (lcm_publish(l, channel.c_str(), data, static_cast<unsigned int>(size)) == 0) return;
  const int e = errno;
  if (e == 0 || e == EMSGSIZE || e == EINVAL)  // LCM refused it (a channel name too long) or it can never fit
    throw BusError("LCM publish failed on " + channel + " (" + std::to_string(size) + " bytes)" +
                   (e ? std::string(": ") + std::strerror(e) : std::string()));
  // The network refused the send (down, unreachable, out of buffers): the message is lost,
  // as a datagram can be, and the protocols above notice and retry (RPC, lockstep resends)
  // or report it (a participant cut off). Counted and logged, never fatal.
  ++lost_sends_;
  if (lost_sends_ <= 5 || lost_sends_ % 1000 == 0)
    SB_WARN("bus", "sending on " << channel << " failed (" << std::strerror(e) << "): message lost (#" << lost_sends_ << ")");
}

UdpmReceiver& LcmBus::receiver(int i) {
  if (lane_urls_[i].empty()) i = 0;
  if (!receivers_[i]) {
    const UdpmAddress a = udpm_address(lane_urls_[i]);
    receivers_[i] = std::make_unique<UdpmReceiver>(a.group, a.port, a.receive_buffer);
  }
  return *receivers_[i];
}

long LcmBus::undecodable() const {
  long n = 0;
  for (const auto& r : receivers_)
    if (r) n += r->reassembler().bad + r->reassembler().incomplete;
  return n;
}

void LcmBus::on_message(const lcm_recv_buf_t* rbuf, const char* channel, void* user) {
  deliver(*static_cast<Sub*>(user), channel, static_cast<const uint8_t*>(rbuf->data), rbuf->data_size);
}

void LcmBus::deliver(Sub& s, const std::string& channel, const uint8_t* data, size_t size) {
  Sub* sub = &s;
  // An exception must not unwind through LCM's C code; a failing handler is logged and
  // the dispatch loop goes on (servers never crash on input).
  // Logged rate-limited (the first 5, then every 1000th, with the count): a sender that
  // keeps sending what fails must not fill the log.
  try {
    sub->handler(channel, data, size);
  } catch (const std::exception& e) {
    if (++sub->failures <= 5 || sub->failures % 1000 == 0)
      SB_ERROR("bus", "handler for " << channel << " failed (#" << sub->failures << "): " << e.what());
  } catch (...) {
    if (++sub->failures <= 5 || sub->failures % 1000 == 0)
      SB_ERROR("bus", "handler for " << channel << " failed (#" << sub->failures << ") with a non-standard exception");
  }
}

int LcmBus::subscribe(const std::string& channel, Handler handler, int queue_capacity) {
  refuse_long_channel(channel);  // (LCM would take the subscription and never deliver)
  auto sub = std::make_unique<Sub>();
  sub->handler = std::move(handler);
  sub->lane = lane_urls_[1].empty() ? 0 : lcm_lane_of(channel);
  const int id = next_id_++;
  if (direct_) {
    receiver(sub->lane);
    by_channel_[channel][id] = sub.get();
    refilter(sub->lane);
  } else {
    sub->lcm_sub = lcm_subscribe(lane(sub->lane), channel.c_str(), &LcmBus::on_message, sub.get());
    if (!sub->lcm_sub) throw BusError("cannot subscribe to " + channel);
    lcm_subscription_set_queue_capacity(sub->lcm_sub, queue_capacity);
  }
  ++lane_subs_[sub->lane];
  subs_[id] = std::move(sub);
  return id;
}

void LcmBus::unsubscribe(int id) {
  auto it = subs_.find(id);
  if (it == subs_.end()) return;
  if (it->second->lcm_sub) lcm_unsubscribe(lanes_[it->second->lane], it->second->lcm_sub);
  bool gone = false;
  for (auto c = by_channel_.begin(); c != by_channel_.end(); ++c)
    if (c->second.erase(id)) {
      if (c->second.empty()) {
        by_channel_.erase(c);
        gone = true;
      }
      break;
    }
  const int lane = it->second->lane;
  --lane_subs_[lane];
  subs_.erase(it);
  if (gone) refilter(lane);
}

void LcmBus::refilter(int lane) {
  if (!direct_ || filter_refused_) return;
  const int socket_lane = lane_urls_[lane].empty() ? 0 : lane;
  if (!receivers_[socket_lane]) return;
  std::vector<std::string> channels;
  for (const auto& [channel, subs] : by_channel_)
    if ((lane_urls_[1].empty() ? 0 : lcm_lane_of(channel)) == socket_lane) channels.push_back(channel);
  std::string why;
  if (!attach_channel_filter(receivers_[socket_lane]->fd(), channels, why)) {
    filter_refused_ = true;  // every datagram wakes this process, as without filters
    SB_WARN("bus", "no channel filter on " << lane_urls_[socket_lane] << ": " << why);
    for (const auto& r : receivers_)
      if (r) detach_channel_filter(r->fd());
  }
}

bool LcmBus::handle_direct(std::chrono::milliseconds timeout) {
  std::array<UdpmReceiver*, 2> rs{nullptr, nullptr};
  int n = 0;
  for (int k = 0; k < 2; ++k) {
    auto& r = receivers_[(k + turn_) % 2];
    if (r) rs[n++] = r.get();
  }
  turn_ ^= 1;
  LcmReassembler::Message m;
  // A flood of datagrams that dispatch nothing (malformed, fragments never completed,
  // channels nobody here reads) must not hold the caller past its timeout: the time is
  // looked at every kJunkCheck of them, and the wait after them is what is left of it.
  constexpr int kJunkCheck = 256;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    for (int k = 0; k < n; ++k) {
      for (int junk = 0;;) {
        const auto got = rs[k]->read(m);
        if (got == UdpmReceiver::Read::kNothing) break;
        auto c = got == UdpmReceiver::Read::kMessage ? by_channel_.find(m.channel) : by_channel_.end();
        if (c != by_channel_.end()) {
          // A handler may unsubscribe (itself or another): deliver to a copy of the list.
          std::vector<int> ids;
          for (const auto& [id, sub] : c->second) ids.push_back(id);
          for (int id : ids) {
            auto s = subs_.find(id);
            if (s != subs_.end()) deliver(*s->second, m.channel, m.data, m.size);
          }
          return true;
        }
        if (++junk % kJunkCheck == 0 && std::chrono::steady_clock::now() >= deadline) return false;
      }
    }
    const auto now = std::chrono::steady_clock::now();
    caught_up_ = now;  // (every socket read empty)
    if (now >= deadline) return false;
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now + std::chrono::microseconds(999));
    pollfd fds[2];
    for (int k = 0; k < n; ++k) fds[k] = {rs[k]->fd(), POLLIN, 0};
    if (::poll(fds, static_cast<nfds_t>(n), static_cast<int>(left.count())) < 0) {
      if (errno == EINTR) return false;  // a signal (e.g. SIGTERM to stop) is not a bus failure
      throw BusError("waiting on the bus " + url_ + " failed: " + std::strerror(errno));
    }
  }
}

bool LcmBus::handle(std::chrono::milliseconds timeout) {
  if (direct_) return handle_direct(timeout);
  const int ms = static_cast<int>(std::max<int64_t>(0, timeout.count()));
  auto check = [&](int r) {
    if (r < 0 && errno == EINTR) return 0;  // a signal (e.g. SIGTERM to stop) is not a bus failure
    if (r < 0) throw BusError("LCM dispatch failed on " + url_ + ": " + std::strerror(errno));
    return r;
  };
  errno = 0;
  if (lane_subs_[1] == 0) return check(lcm_handle_timeout(lane(0), ms)) > 0;
  if (lane_subs_[0] == 0) return check(lcm_handle_timeout(lane(1), ms)) > 0;
  pollfd fds[2] = {{lcm_get_fileno(lane(0)), POLLIN, 0}, {lcm_get_fileno(lane(1)), POLLIN, 0}};
  if (check(::poll(fds, 2, ms)) <= 0) return false;
  bool handled = false;
  for (int i = 0; i < 2; ++i)
    if (fds[i].revents & POLLIN) handled |= check(lcm_handle_timeout(lanes_[i], 0)) > 0;
  return handled;
}

}  // namespace skillbus
