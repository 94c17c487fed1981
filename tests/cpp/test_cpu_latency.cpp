// A CPU latency request (skillbus/apps/cpu_latency.hpp) on a file standing in for the
// kernel's device: what it writes, what it reads back, what it refuses and how it names
// why, and that nothing stays open after it. (The real device: test_lockstep_processes.py.)
#include <gtest/gtest.h>
#include <dirent.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

#include "skillbus/apps/cpu_latency.hpp"

using skillbus::apps::CpuLatencyRequest;

namespace {

std::string temp_device() {
  char path[] = "/tmp/cpu_latency_testXXXXXX";
  const int fd = ::mkstemp(path);
  EXPECT_GE(fd, 0);
  ::close(fd);
  return path;
}

std::string contents(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

int open_fds() {
  int n = 0;
  if (DIR* d = ::opendir("/proc/self/fd")) {
    while (::readdir(d)) ++n;
    ::closedir(d);
  }
  return n;
}

}  // namespace

TEST(CpuLatency, WritesTheRequestAsA32BitIntegerAndReadsBackWhatTheDeviceSays) {
  const std::string dev = temp_device();
  {
    CpuLatencyRequest r(7, dev);
    EXPECT_EQ(r.requested_us(), 7);
    const int32_t seven = 7;
    EXPECT_EQ(contents(dev), std::string(reinterpret_cast<const char*>(&seven), sizeof seven));
    ASSERT_TRUE(r.in_force_us().has_value());
    EXPECT_EQ(*r.in_force_us(), 7);
  }
  std::remove(dev.c_str());
}

TEST(CpuLatency, ADeviceThatCannotBeOpenedIsNamedWithWhy) {
  try {
    CpuLatencyRequest r(0, "/nonexistent/cpu_dma_latency");
    FAIL() << "a missing device was taken";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent/cpu_dma_latency: cannot open: No such file or directory");
  }
}

TEST(CpuLatency, AValueOutOfRangeIsRefusedBeforeTheDeviceIsTouched) {
  const std::string dev = temp_device();
  EXPECT_THROW(CpuLatencyRequest(-1, dev), std::invalid_argument);
  EXPECT_THROW(CpuLatencyRequest(1'000'001, dev), std::invalid_argument);
  EXPECT_EQ(contents(dev), "");  // nothing written
  std::remove(dev.c_str());
}

TEST(CpuLatency, TheDeviceIsClosedWhenTheRequestEnds) {
  // (The kernel drops a request when its file is closed: nothing may keep it open.)
  const std::string dev = temp_device();
  const int before = open_fds();
  {
    CpuLatencyRequest r(0, dev);
    EXPECT_EQ(open_fds(), before + 1);
    (void)r.in_force_us();  // (reads through a descriptor of its own, closed again)
    EXPECT_EQ(open_fds(), before + 1);
  }
  EXPECT_EQ(open_fds(), before);
  std::remove(dev.c_str());
}
