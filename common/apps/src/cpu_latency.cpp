#include "skillbus/apps/cpu_latency.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "skillbus/apps/lifecycle.hpp"

namespace skillbus::apps {

namespace {

constexpr int64_t kMaxUs = 1'000'000;

std::string why(const std::string& device, const char* what) {
  std::string s = device + ": " + what + ": " + std::strerror(errno);
  if (errno == EACCES || errno == EPERM)
    s += " (the device is root's: run as root, or give your group write access with a udev rule)";
  return s;
}

}  // namespace

CpuLatencyRequest::CpuLatencyRequest(int64_t us, const std::string& device) : device_(device), requested_us_(us) {
  if (us < 0 || us > kMaxUs)
    throw std::invalid_argument("a CPU latency of " + std::to_string(us) + " us: expected 0 to 1000000");
  fd_ = ::open(device.c_str(), O_RDWR | O_CLOEXEC);
  if (fd_ < 0) throw std::runtime_error(why(device, "cannot open"));
  // The device takes the request as a binary 32-bit integer of microseconds.
  const int32_t value = static_cast<int32_t>(us);
  if (::write(fd_, &value, sizeof value) != static_cast<ssize_t>(sizeof value)) {
    const std::string text = why(device, "cannot write the request");
    ::close(fd_);
    fd_ = -1;
    throw std::runtime_error(text);
  }
}

CpuLatencyRequest::~CpuLatencyRequest() {
  if (fd_ >= 0) ::close(fd_);  // the kernel drops the request
}

int64_t CpuLatencyRequest::in_force_us() const {
  int32_t value = 0;
  if (::pread(fd_, &value, sizeof value, 0) != static_cast<ssize_t>(sizeof value)) return -1;
  return value;
}

std::unique_ptr<CpuLatencyRequest> hold_cpu_latency_or_exit(const char* program, int64_t us) {
  if (us < 0) return nullptr;
  try {
    return std::make_unique<CpuLatencyRequest>(us);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: cannot start: --cpu-latency-us %lld: %s\n", program, static_cast<long long>(us),
                 e.what());
    std::exit(kStartError);
  }
}

}  // namespace skillbus::apps
