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

// `err`: the errno of the failed call, saved before anything else can change it.
std::string why(const std::string& device, const char* what, int err) {
  std::string s = device + ": " + what + ": " + std::strerror(err);
  if (err == EACCES || err == EPERM)
    s += " (the device is root's: run as root, or give your group write access with a udev rule)";
  return s;
}

}  // namespace

CpuLatencyRequest::CpuLatencyRequest(int64_t us, const std::string& device) : device_(device), requested_us_(us) {
  if (us < 0 || us > kMaxUs)
    throw std::invalid_argument("a CPU latency of " + std::to_string(us) + " us: expected 0 to 1000000");
  // Write access is all a request needs (what a udev rule for a group would give).
  fd_ = ::open(device.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd_ < 0) {
    const int err = errno;
    throw std::runtime_error(why(device, "cannot open", err));
  }
  // The device takes the request as a binary 32-bit integer of microseconds.
  const int32_t value = static_cast<int32_t>(us);
  const ssize_t n = ::write(fd_, &value, sizeof value);
  if (n != static_cast<ssize_t>(sizeof value)) {
    const int err = n < 0 ? errno : EIO;  // (a short write: the kernel took no request)
    ::close(fd_);
    fd_ = -1;
    throw std::runtime_error(why(device, "cannot write the request", err));
  }
}

CpuLatencyRequest::~CpuLatencyRequest() {
  if (fd_ >= 0) ::close(fd_);  // the kernel drops the request
}

std::optional<int64_t> CpuLatencyRequest::in_force_us() const {
  // Read through a descriptor of its own: the request's may be write-only.
  const int fd = ::open(device_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return std::nullopt;
  int32_t value = 0;
  const bool ok = ::read(fd, &value, sizeof value) == static_cast<ssize_t>(sizeof value);
  ::close(fd);
  if (!ok) return std::nullopt;
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
