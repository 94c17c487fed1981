#include "lcm_bus.hpp"

#include <cerrno>
#include <cstring>

#include "skillbus/log.hpp"

namespace skillbus {

LcmBus::LcmBus(const std::string& url) : url_(url) {
  lcm_ = lcm_create(url.c_str());
  if (!lcm_)
    throw BusError("cannot open LCM at '" + url +
                   "' (for udpm:// the host needs a multicast route, e.g. `ip route add 224.0.0.0/4 dev lo`)");
}

LcmBus::~LcmBus() {
  for (auto& [id, sub] : subs_) lcm_unsubscribe(lcm_, sub->lcm_sub);
  lcm_destroy(lcm_);
}

void LcmBus::publish(const std::string& channel, const void* data, size_t size) {
  if (lcm_publish(lcm_, channel.c_str(), data, static_cast<unsigned int>(size)) != 0)
    throw BusError("LCM publish failed on " + channel + " (" + std::to_string(size) + " bytes)");
}

void LcmBus::on_message(const lcm_recv_buf_t* rbuf, const char* channel, void* user) {
  auto* sub = static_cast<Sub*>(user);
  // An exception must not unwind through LCM's C code; a failing handler is logged and
  // the dispatch loop goes on (servers never crash on input).
  try {
    sub->handler(channel, static_cast<const uint8_t*>(rbuf->data), rbuf->data_size);
  } catch (const std::exception& e) {
    SB_ERROR("bus", "handler for " << channel << " failed: " << e.what());
  } catch (...) {
    SB_ERROR("bus", "handler for " << channel << " failed with a non-standard exception");
  }
}

int LcmBus::subscribe(const std::string& channel, Handler handler, int queue_capacity) {
  auto sub = std::make_unique<Sub>();
  sub->handler = std::move(handler);
  sub->lcm_sub = lcm_subscribe(lcm_, channel.c_str(), &LcmBus::on_message, sub.get());
  if (!sub->lcm_sub) throw BusError("cannot subscribe to " + channel);
  lcm_subscription_set_queue_capacity(sub->lcm_sub, queue_capacity);
  const int id = next_id_++;
  subs_[id] = std::move(sub);
  return id;
}

void LcmBus::unsubscribe(int id) {
  auto it = subs_.find(id);
  if (it == subs_.end()) return;
  lcm_unsubscribe(lcm_, it->second->lcm_sub);
  subs_.erase(it);
}

bool LcmBus::handle(std::chrono::milliseconds timeout) {
  const int ms = static_cast<int>(std::max<int64_t>(0, timeout.count()));
  errno = 0;
  const int r = lcm_handle_timeout(lcm_, ms);
  if (r < 0 && errno == EINTR) return false;  // a signal (e.g. SIGTERM to stop) is not a bus failure
  if (r < 0) throw BusError("LCM dispatch failed on " + url_ + ": " + std::strerror(errno));
  return r > 0;
}

}  // namespace skillbus
