// A CPU latency request held while a program runs (Linux PM QoS, /dev/cpu_dma_latency).
//
// Why a lockstep master asks for one: every frame its clock and state wake the
// participants on another core, and on a core that sleeps in a halt state such a wake-up
// costs the sender an inter-processor interrupt (on a virtual machine it goes through the
// host: about 20-30 µs here) and the sleeper its idle state's exit. Asked for 0 µs, the
// kernel keeps idle cores polling instead of halting, and a wake-up is a flag the polling
// core sees at once: a round trip between two pinned processes 150 -> 35 µs, the demo's
// frames about 6 % shorter (docs/lockstep.md, "Idle cores that poll"). It costs power:
// the idle cores spin while the request is held.
//
// The kernel holds the request while the device stays open and drops it when the
// process ends, however it ends: nothing to undo after a crash.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

namespace skillbus::apps {

class CpuLatencyRequest {
 public:
  static constexpr const char* kDevice = "/dev/cpu_dma_latency";

  // Opens the device and asks for `us` µs (0 to 1 s). Throws std::runtime_error naming
  // the device and why (e.g. "Permission denied": it is root's unless a udev rule says
  // otherwise), or std::invalid_argument for a value out of range.
  explicit CpuLatencyRequest(int64_t us, const std::string& device = kDevice);
  ~CpuLatencyRequest();
  CpuLatencyRequest(const CpuLatencyRequest&) = delete;
  CpuLatencyRequest& operator=(const CpuLatencyRequest&) = delete;

  int64_t requested_us() const { return requested_us_; }
  // The latency the kernel applies now: the smallest of every holder's request (none when
  // this process may not read the device: a request needs only write access).
  std::optional<int64_t> in_force_us() const;

 private:
  std::string device_;
  int fd_ = -1;
  int64_t requested_us_ = 0;
};

// The request of a program's --cpu-latency-us (apps::add_cpu_latency_option): none when
// the option was not given (us < 0); a request that cannot be held ends the program with
// "<program>: cannot start: --cpu-latency-us N: <why>" and kStartError.
std::unique_ptr<CpuLatencyRequest> hold_cpu_latency_or_exit(const char* program, int64_t us);

}  // namespace skillbus::apps
