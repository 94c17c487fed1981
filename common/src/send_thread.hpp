// A bus's sends made from a thread of their own, on cores the caller names.
//
// On a virtual machine, sending a datagram that wakes a process sleeping on another core
// costs the sender several microseconds per woken process (the wake-up goes through the
// scheduler of the other core, through the host). The lockstep master sends each frame's
// state and clock that way to every participant, on the physics' own core and before
// its step: the demo's physics server spent about 0.03 ms a frame on it (docs/lockstep.md,
// "Sending from the participants' core"). Handed to this thread, pinned to the
// participants' core, a frame's datagrams cost the physics' core one wake-up of the
// thread, and their fan-out happens where the receivers run.
//
// Messages go out in the order they were pushed (one FIFO, one thread): what one
// process publishes keeps its order, as a direct send does.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace skillbus {

class SendThread {
 public:
  // `send` sends one message (called on the thread, in push order) and returns false
  // when the network refused it (counted in lost()). `cpus`: where the thread runs (empty:
  // wherever the kernel puts it); a set the kernel refuses is logged and left to it.
  SendThread(std::vector<int> cpus, std::function<bool(int lane, const std::string& channel,
                                                        const std::vector<uint8_t>& data)> send);
  // Sends what is still queued, then ends the thread.
  ~SendThread();
  SendThread(const SendThread&) = delete;
  SendThread& operator=(const SendThread&) = delete;

  void push(int lane, const std::string& channel, const void* data, size_t size);
  // Returns once everything pushed before the call has been sent.
  void flush();
  // Messages the network refused (`send` returned false).
  long lost() const { return lost_.load(std::memory_order_relaxed); }
  // Whether the thread runs on the cores asked for ("" when it does, else why not).
  const std::string& placement_error() const { return placement_error_; }

 private:
  struct Message {
    int lane;
    std::string channel;
    std::vector<uint8_t> data;
  };
  void run(std::vector<int> cpus);

  std::function<bool(int, const std::string&, const std::vector<uint8_t>&)> send_;
  std::mutex mu_;
  std::condition_variable ready_, sent_;
  std::deque<Message> queue_;
  uint64_t pushed_ = 0, done_ = 0;  // counts, under mu_: flush() waits for done_ to reach pushed_
  bool stop_ = false;
  std::atomic<long> lost_{0};
  std::string placement_error_;
  bool placed_ = false;  // (placement_error_ is written once by the thread, before placed_)
  std::condition_variable placed_cv_;
  std::thread thread_;
};

}  // namespace skillbus
