// The LCM backend of Bus, on LCM's C API (it exposes per-subscription queue capacity).
//
// Two lanes. LCM's UDP multicast delivers every datagram of a group and port to every
// process on it, which then throws away what it did not subscribe to. Many-to-one
// traffic (lockstep acks and joins: channels ending in _ACK or _JOIN) would so wake
// every participant for every other participant's ack. Those channels travel on lane 1,
// the same group on port+1, which only their receiver (the master) listens to; all
// other channels use lane 0, the URL as given. memq:// has one lane.
//
// On udpm:// the bus publishes with LCM and receives on the dispatching thread
// (UdpmReceiver: no receive thread, no pipe); the socket's receive buffer is the queue.
// Other URLs (memq://, file://) use LCM both ways.
#pragma once

#include <lcm/lcm.h>

#include <array>
#include <map>
#include <memory>

#include "skillbus/bus.hpp"
#include "udpm_receiver.hpp"

namespace skillbus {

class LcmBus : public Bus {
 public:
  explicit LcmBus(const std::string& url);
  ~LcmBus() override;
  void publish(const std::string& channel, const void* data, size_t size) override;
  int subscribe(const std::string& channel, Handler handler, int queue_capacity = 10000) override;
  void unsubscribe(int subscription_id) override;
  bool handle(std::chrono::milliseconds timeout) override;
  std::string url() const override { return url_; }
  std::chrono::steady_clock::time_point caught_up_at() const override {
    return direct_ ? caught_up_ : std::chrono::steady_clock::now();  // (LCM's own thread: cannot tell)
  }

 private:
  struct Sub {
    Handler handler;
    int lane = 0;
    lcm_subscription_t* lcm_sub = nullptr;
    long failures = 0;  // handler failures, logged rate-limited
  };
  static void on_message(const lcm_recv_buf_t* rbuf, const char* channel, void* user);
  static void deliver(Sub& sub, const std::string& channel, const uint8_t* data, size_t size);
  lcm_t* lane(int i);  // opened on first use
  UdpmReceiver& receiver(int i);  // opened on first use
  bool handle_direct(std::chrono::milliseconds timeout);
  void refilter(int lane);  // the lane's socket filter: its channels now (channel_filter.hpp)

  std::string url_;
  std::chrono::steady_clock::time_point caught_up_ = std::chrono::steady_clock::now();  // every socket read empty
  std::array<std::string, 2> lane_urls_;
  std::array<lcm_t*, 2> lanes_{nullptr, nullptr};
  std::array<int, 2> lane_subs_{0, 0};
  int next_id_ = 1;
  std::map<int, std::unique_ptr<Sub>> subs_;
  bool direct_ = false;  // udpm://: received by receivers_, not by LCM
  std::array<std::unique_ptr<UdpmReceiver>, 2> receivers_;
  std::map<std::string, std::map<int, Sub*>> by_channel_;  // direct: subscriptions by channel
  int turn_ = 0;  // the lane read first by the next handle(): neither starves the other
  bool filter_refused_ = false;  // the kernel refused a filter once: logged, not tried again

 public:
  // Datagrams that were no LCM message, and fragmented messages that lost a fragment.
  long undecodable() const;
  // Messages the network refused to send (logged; the protocols above retry or report).
  long lost_sends() const { return lost_sends_; }

 private:
  long lost_sends_ = 0;
};

// Lane of a channel: 1 for many-to-one channels (names ending in _ACK or _JOIN), else 0.
int lcm_lane_of(const std::string& channel);
// URL of lane 1 for a udpm:// URL (port+1), or "" when the URL has a single lane.
std::string lcm_lane1_url(const std::string& url);

// Every udpm:// socket asks for a large receive buffer unless the URL names one
// (recv_buf_size=): with the kernel's default (about 208 KB) a reply of a few UDP
// fragments, or a burst that arrives while the process is busy, overflows it and is lost
// whole. The kernel caps the request at net.core.rmem_max: a cap below the request is
// warned about once per process, naming the sysctl.
constexpr long kLcmReceiveBuffer = 4L << 20;
// `url` with recv_buf_size=min(kLcmReceiveBuffer, `rmem_max`) added, for udpm:// URLs
// that do not set it (rmem_max <= 0: unknown, the request as it is).
std::string lcm_url_with_receive_buffer(const std::string& url, long rmem_max);
// net.core.rmem_max, or -1 when it cannot be read.
long kernel_receive_buffer_cap();

}  // namespace skillbus
