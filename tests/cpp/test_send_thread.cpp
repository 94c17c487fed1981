// SendThread: a bus's sends from a thread of their own (common/src/send_thread.hpp).
#include <gtest/gtest.h>
#include <sched.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "send_thread.hpp"
#include "skillbus/bus.hpp"

using skillbus::SendThread;

namespace {

struct Sent {
  int lane;
  std::string channel;
  std::string data;
};

// Records what the thread sends, and on which thread it runs.
struct Recorder {
  std::mutex mu;
  std::vector<Sent> sent;
  std::thread::id thread;
  int cpu = -1;
  std::function<bool(int, const std::string&, const std::vector<uint8_t>&)> send(bool ok = true) {
    return [this, ok](int lane, const std::string& ch, const std::vector<uint8_t>& d) {
      std::lock_guard<std::mutex> lock(mu);
      sent.push_back({lane, ch, std::string(d.begin(), d.end())});
      thread = std::this_thread::get_id();
      cpu = sched_getcpu();
      return ok;
    };
  }
};

std::vector<int> allowed_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  sched_getaffinity(0, sizeof set, &set);
  std::vector<int> out;
  for (int c = 0; c < CPU_SETSIZE; ++c)
    if (CPU_ISSET(c, &set)) out.push_back(c);
  return out;
}

}  // namespace

TEST(SendThread, SendsEverythingInTheOrderPushedOnItsOwnThread) {
  Recorder r;
  {
    SendThread t({}, r.send());
    for (int i = 0; i < 2000; ++i) {
      const std::string payload = "m" + std::to_string(i);
      t.push(i % 2, "SB_CH" + std::to_string(i % 3), payload.data(), payload.size());
    }
    t.flush();
    std::lock_guard<std::mutex> lock(r.mu);
    ASSERT_EQ(r.sent.size(), 2000u);  // flush() returned: every one pushed before it was sent
    for (int i = 0; i < 2000; ++i) {
      EXPECT_EQ(r.sent[i].data, "m" + std::to_string(i));
      EXPECT_EQ(r.sent[i].lane, i % 2);
      EXPECT_EQ(r.sent[i].channel, "SB_CH" + std::to_string(i % 3));
    }
    EXPECT_NE(r.thread, std::this_thread::get_id());
    EXPECT_EQ(t.lost(), 0);
  }
}

TEST(SendThread, ThePushedBytesAreCopiedAtOnce) {
  Recorder r;
  SendThread t({}, r.send());
  std::string buffer = "first";
  t.push(0, "SB_X", buffer.data(), buffer.size());
  buffer = "other";  // (a caller reuses its buffer as soon as publish() returns)
  t.flush();
  std::lock_guard<std::mutex> lock(r.mu);
  ASSERT_EQ(r.sent.size(), 1u);
  EXPECT_EQ(r.sent[0].data, "first");
}

TEST(SendThread, ItsEndSendsWhatIsStillQueued) {
  Recorder r;
  std::atomic<bool> release{false};
  {
    // A send that blocks until released: the pushes pile up behind it.
    SendThread t({}, [&](int lane, const std::string& ch, const std::vector<uint8_t>& d) {
      while (!release.load()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
      return r.send()(lane, ch, d);
    });
    for (int i = 0; i < 50; ++i) t.push(0, "SB_X", "x", 1);
    release = true;
  }  // (the destructor returns only once all 50 went out)
  std::lock_guard<std::mutex> lock(r.mu);
  EXPECT_EQ(r.sent.size(), 50u);
}

TEST(SendThread, RefusedSendsAreCounted) {
  Recorder r;
  SendThread t({}, r.send(false));
  for (int i = 0; i < 7; ++i) t.push(0, "SB_X", "x", 1);
  t.flush();
  EXPECT_EQ(t.lost(), 7);
}

TEST(SendThread, RunsOnTheCoreAskedFor) {
  const std::vector<int> cpus = allowed_cpus();
  ASSERT_FALSE(cpus.empty());
  const int cpu = cpus.back();
  Recorder r;
  SendThread t({cpu}, r.send());
  EXPECT_EQ(t.placement_error(), "");
  for (int i = 0; i < 20; ++i) t.push(0, "SB_X", "x", 1);
  t.flush();
  std::lock_guard<std::mutex> lock(r.mu);
  EXPECT_EQ(r.cpu, cpu);
}

TEST(SendThread, ACoreTheKernelRefusesIsNamedAndItSendsAnyway) {
  const long online = sysconf(_SC_NPROCESSORS_CONF);
  ASSERT_LT(online, CPU_SETSIZE - 1);
  Recorder r;
  SendThread t({CPU_SETSIZE - 1}, r.send());  // (no such core on this machine)
  EXPECT_NE(t.placement_error(), "");
  t.push(0, "SB_X", "x", 1);
  t.flush();
  std::lock_guard<std::mutex> lock(r.mu);
  EXPECT_EQ(r.sent.size(), 1u);
}

// Bus::send_from_thread is udpm:// only: memq:// delivers in the sender's thread, where
// its handlers would then run; it says so and goes on sending as before.
TEST(SendThread, AMemqBusSaysItSendsOnTheCallersThread) {
  auto bus = skillbus::open_bus("memq://");
  const std::string why = bus->send_from_thread({0});
  EXPECT_NE(why.find("only a udpm:// bus sends from a thread"), std::string::npos) << why;
  int got = 0;
  bus->subscribe("SB_X", [&](const std::string&, const uint8_t*, size_t) { ++got; });
  bus->publish("SB_X", "x", 1);
  bus->handle(std::chrono::milliseconds(100));
  EXPECT_EQ(got, 1);
}
