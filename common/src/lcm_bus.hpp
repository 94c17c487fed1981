// The LCM backend of Bus, on LCM's C API (it exposes per-subscription queue capacity).
#pragma once

#include <lcm/lcm.h>

#include <map>
#include <memory>

#include "skillbus/bus.hpp"

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

 private:
  struct Sub {
    Handler handler;
    lcm_subscription_t* lcm_sub = nullptr;
  };
  static void on_message(const lcm_recv_buf_t* rbuf, const char* channel, void* user);

  std::string url_;
  lcm_t* lcm_ = nullptr;
  int next_id_ = 1;
  std::map<int, std::unique_ptr<Sub>> subs_;
};

}  // namespace skillbus
