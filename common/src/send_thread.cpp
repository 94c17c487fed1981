#include "send_thread.hpp"

#include <pthread.h>
#include <sched.h>

#include <cerrno>
#include <cstring>

namespace skillbus {

SendThread::SendThread(std::vector<int> cpus,
                       std::function<bool(int, const std::string&, const std::vector<uint8_t>&)> send)
    : send_(std::move(send)) {
  thread_ = std::thread([this, cpus]() mutable { run(std::move(cpus)); });
  // The placement is known before the constructor returns (the caller logs it).
  std::unique_lock<std::mutex> lock(mu_);
  placed_cv_.wait(lock, [&] { return placed_; });
}

SendThread::~SendThread() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stop_ = true;
  }
  ready_.notify_one();
  thread_.join();
}

void SendThread::push(int lane, const std::string& channel, const void* data, size_t size) {
  const auto* p = static_cast<const uint8_t*>(data);
  {
    std::lock_guard<std::mutex> lock(mu_);
    queue_.push_back(Message{lane, channel, std::vector<uint8_t>(p, p + size)});
    ++pushed_;
  }
  // (no system call when the thread is busy sending: it takes the rest of a frame's
  // messages without being woken again)
  ready_.notify_one();
}

void SendThread::flush() {
  std::unique_lock<std::mutex> lock(mu_);
  const uint64_t target = pushed_;
  sent_.wait(lock, [&] { return done_ >= target; });
}

void SendThread::run(std::vector<int> cpus) {
  std::string error;
  if (!cpus.empty()) {
    cpu_set_t set;
    CPU_ZERO(&set);
    for (int c : cpus)
      if (c >= 0 && c < CPU_SETSIZE) CPU_SET(c, &set);
    const int rc = pthread_setaffinity_np(pthread_self(), sizeof set, &set);
    if (rc != 0) error = std::strerror(rc);
  }
  {
    std::lock_guard<std::mutex> lock(mu_);
    placement_error_ = error;
    placed_ = true;
  }
  placed_cv_.notify_all();
  std::unique_lock<std::mutex> lock(mu_);
  for (;;) {
    ready_.wait(lock, [&] { return stop_ || !queue_.empty(); });
    if (queue_.empty()) return;  // stopped, and everything sent
    Message m = std::move(queue_.front());
    queue_.pop_front();
    lock.unlock();
    const bool ok = send_(m.lane, m.channel, m.data);
    if (!ok) lost_.fetch_add(1, std::memory_order_relaxed);
    lock.lock();
    ++done_;
    sent_.notify_all();
  }
}

}  // namespace skillbus
