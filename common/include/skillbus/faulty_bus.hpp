// A bus decorator that drops every n-th message it publishes on each channel (so an
// RPC loses every third request and every third reply). For tests of the layers above
// the bus (RPC retries, lockstep loss reporting); never used in production paths.
#pragma once

#include <map>

#include "skillbus/bus.hpp"

namespace skillbus {

class DropEveryNthBus : public Bus {
 public:
  // With `only_channel` set, only that channel loses messages.
  DropEveryNthBus(std::unique_ptr<Bus> inner, int n, std::string only_channel = "")
      : inner_(std::move(inner)), n_(n), only_(std::move(only_channel)) {}
  void publish(const std::string& ch, const void* data, size_t size) override {
    const long k = ++published_[ch];
    if (n_ > 0 && k % n_ == 0 && (only_.empty() || ch == only_)) { ++dropped_; return; }
    inner_->publish(ch, data, size);
  }
  int subscribe(const std::string& ch, Handler h, int cap = 10000) override { return inner_->subscribe(ch, std::move(h), cap); }
  void unsubscribe(int id) override { inner_->unsubscribe(id); }
  bool handle(std::chrono::milliseconds t) override { return inner_->handle(t); }
  std::string url() const override { return inner_->url(); }
  std::chrono::steady_clock::time_point caught_up_at() const override { return inner_->caught_up_at(); }
  long dropped() const { return dropped_; }

 private:
  std::unique_ptr<Bus> inner_;
  int n_;
  std::string only_;
  std::map<std::string, long> published_;
  long dropped_ = 0;
};

}  // namespace skillbus
