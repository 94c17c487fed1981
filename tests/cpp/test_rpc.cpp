#include <gtest/gtest.h>

#include <map>

#include "skillbus/faulty_bus.hpp"
#include "skillbus/rpc.hpp"
#include "skillbus_msgs/rpc_counter_t.hpp"
#include "skillbus_msgs/rpc_reply_t.hpp"
#include "skillbus_msgs/rpc_request_t.hpp"

using namespace skillbus;
using namespace std::chrono_literals;
using skillbus_msgs::rpc_counter_t;
using skillbus_msgs::rpc_reply_t;

namespace {

// Server and client share one in-process bus; the client's wait dispatches both.
struct CounterFixture {
  explicit CounterFixture(int drop_every = 0)
      : bus(std::make_unique<DropEveryNthBus>(open_bus("memq://"), drop_every)), server(*bus, "counter") {
    server.add_method<rpc_counter_t, rpc_counter_t>("add", [this](const rpc_counter_t& r) {
      auto& c = counters[r.key];
      c.value += r.amount;
      c.writes += 1;
      return c;
    });
    server.add_method<rpc_counter_t, rpc_counter_t>("boom", [](const rpc_counter_t&) -> rpc_counter_t {
      throw std::runtime_error("the method exploded");
    });
  }
  static rpc_counter_t add(const std::string& key, int64_t amount) {
    rpc_counter_t r{};
    r.key = key;
    r.amount = amount;
    return r;
  }
  std::unique_ptr<DropEveryNthBus> bus;
  RpcServer server;
  std::map<std::string, rpc_counter_t> counters;
};

}  // namespace

TEST(Rpc, ChannelsFollowTheNamingRule) {
  EXPECT_EQ(rpc_request_channel("wm"), "SB_WM_REQ");
  EXPECT_EQ(rpc_reply_channel("wm"), "SB_WM_REP");
}

TEST(Rpc, CallReturnsTheMethodsReply) {
  CounterFixture f;
  RpcClient client(*f.bus, "counter", "test");
  auto r1 = client.call<rpc_counter_t>("add", CounterFixture::add("a", 5));
  auto r2 = client.call<rpc_counter_t>("add", CounterFixture::add("a", 7));
  EXPECT_EQ(r1.value, 5);
  EXPECT_EQ(r2.value, 12);
  EXPECT_EQ(r2.writes, 2);
}

TEST(Rpc, EveryWriteAppliedExactlyOnceWhenEveryThirdMessageIsDropped) {
  CounterFixture f(3);
  RpcClient client(*f.bus, "counter", "test");
  CallOptions opts;
  opts.retry_interval = 5ms;
  for (int i = 0; i < 300; ++i) client.call<rpc_counter_t>("add", CounterFixture::add("k", 1), opts);
  EXPECT_EQ(f.counters["k"].writes, 300);
  EXPECT_EQ(f.counters["k"].value, 300);
  EXPECT_GT(f.server.duplicates(), 0);  // retries of lost replies were answered from memory
  EXPECT_GT(client.retries(), 0);
}

TEST(Rpc, UnknownMethodIsATypedError) {
  CounterFixture f;
  RpcClient client(*f.bus, "counter", "test");
  try {
    client.call<rpc_counter_t>("nope", CounterFixture::add("a", 1));
    FAIL() << "expected RpcRemoteError";
  } catch (const RpcRemoteError& e) {
    EXPECT_EQ(e.status, rpc_reply_t::UNKNOWN_METHOD);
    EXPECT_NE(std::string(e.what()).find("nope"), std::string::npos);
  }
}

TEST(Rpc, MethodExceptionComesBackAsErrorWithItsMessage) {
  CounterFixture f;
  RpcClient client(*f.bus, "counter", "test");
  try {
    client.call<rpc_counter_t>("boom", CounterFixture::add("a", 1));
    FAIL() << "expected RpcRemoteError";
  } catch (const RpcRemoteError& e) {
    EXPECT_EQ(e.status, rpc_reply_t::ERROR);
    EXPECT_NE(std::string(e.what()).find("the method exploded"), std::string::npos);
  }
}

TEST(Rpc, UndecodablePayloadIsABadRequest) {
  CounterFixture f;
  RpcClient client(*f.bus, "counter", "test");
  try {
    client.call_raw("add", Bytes{1, 2, 3});
    FAIL() << "expected RpcRemoteError";
  } catch (const RpcRemoteError& e) {
    EXPECT_EQ(e.status, rpc_reply_t::BAD_REQUEST);
  }
  EXPECT_TRUE(f.counters.empty());
}

TEST(Rpc, NoServerTimesOutWithinTheDeadline) {
  auto bus = open_bus("memq://");
  RpcClient client(*bus, "nobody", "test");
  CallOptions opts;
  opts.timeout = 300ms;
  opts.retry_interval = 50ms;
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_THROW(client.call<rpc_counter_t>("add", CounterFixture::add("a", 1), opts), RpcTimeout);
  const auto took = std::chrono::steady_clock::now() - t0;
  EXPECT_GE(took, 290ms);
  EXPECT_LT(took, 1000ms);
}

TEST(Rpc, GarbageOnTheRequestChannelIsCountedNotFatal) {
  CounterFixture f;
  const uint8_t junk[] = {0xde, 0xad, 0xbe, 0xef, 0, 1, 2, 3, 4, 5, 6, 7, 8};
  for (int i = 0; i < 5; ++i) f.bus->publish("SB_COUNTER_REQ", junk, sizeof junk);
  f.bus->publish("SB_COUNTER_REQ", junk, 2);
  RpcClient client(*f.bus, "counter", "test");
  EXPECT_EQ(client.call<rpc_counter_t>("add", CounterFixture::add("a", 2)).value, 2);
  EXPECT_EQ(f.server.bad_input().total(), 6);
}

TEST(Rpc, ALargeReplyArrivesInChunksWhenEveryThirdMessageIsDropped) {
  auto bus = std::make_unique<DropEveryNthBus>(open_bus("memq://"), 3);
  RpcServer server(*bus, "big");
  int runs = 0;
  std::string big;
  for (int i = 0; i < 1'000'000; ++i) big.push_back(static_cast<char>('A' + i % 26));
  server.add_method<rpc_counter_t, rpc_counter_t>("echo", [&runs, &big](const rpc_counter_t& r) {
    ++runs;  // a small request, a 1 MB reply
    rpc_counter_t out = r;
    out.key = big;
    return out;
  });
  RpcClient client(*bus, "big", "test");
  rpc_counter_t req{};
  req.amount = 7;
  CallOptions opts;
  opts.retry_interval = 5ms;
  opts.timeout = 10s;
  const auto rep = client.call<rpc_counter_t>("echo", req, opts);
  EXPECT_EQ(rep.key, big);
  EXPECT_EQ(rep.amount, 7);
  EXPECT_EQ(runs, 1);
  EXPECT_GE(server.chunks_pulled(), 20);  // 21 chunks after the first, some asked twice
}

TEST(Rpc, ARetryThatArrivesWhileTheCallStillRunsDoesNotRunItAgain) {
  // A method that waits pumps the bus (a nested call); the client's retry of the same
  // call arrives meanwhile. It must not run the method a second time.
  auto bus = open_bus("memq://");
  std::vector<Bytes> raw;
  bus->subscribe(rpc_request_channel("slow"), [&](const std::string&, const uint8_t* d, size_t n) { raw.emplace_back(d, d + n); });
  RpcServer server(*bus, "slow");
  int runs = 0;
  server.add_method<rpc_counter_t, rpc_counter_t>("run", [&](const rpc_counter_t& r) {
    if (++runs == 1) {
      bus->publish(rpc_request_channel("slow"), raw.at(0).data(), raw.at(0).size());  // the retry, meanwhile
      for (int i = 0; i < 20; ++i) bus->handle(10ms);
    }
    return r;
  });
  RpcClient client(*bus, "slow", "test");
  EXPECT_EQ(client.call<rpc_counter_t>("run", CounterFixture::add("a", 1)).key, "a");
  EXPECT_EQ(runs, 1);
  EXPECT_GE(server.duplicates(), 1);
}

// A method that cannot answer yet defers: the request is kept, its retries run nothing,
// and it runs once, answering the waiting client, when the server retries it.
TEST(Rpc, ADeferredCallRunsOnceWhenRetriedAndItsRetriesMeanwhileRunNothing) {
  CounterFixture f;
  bool ready = false;
  int deferrals = 0, runs = 0, seen = 0;
  f.server.add_method<rpc_counter_t, rpc_counter_t>("when_ready", [&](const rpc_counter_t& r) {
    if (!ready) {
      ++deferrals;
      throw RpcDefer();
    }
    ++runs;
    rpc_counter_t out = r;
    out.value = 42;
    return out;
  });
  // Stands in for a participant finishing its frame: on the third request (two retries
  // later) the method can answer.
  const int side = f.bus->subscribe(rpc_request_channel("counter"), [&](const std::string&, const uint8_t*, size_t) {
    if (++seen == 3) {
      ready = true;
      f.server.retry_deferred();
    }
  });
  RpcClient client(*f.bus, "counter", "test");
  CallOptions o;
  o.retry_interval = 20ms;
  o.timeout = 3000ms;
  const auto r = client.call<rpc_counter_t>("when_ready", CounterFixture::add("x", 1), o);
  EXPECT_EQ(r.value, 42);
  EXPECT_EQ(deferrals, 1);
  EXPECT_EQ(runs, 1);
  EXPECT_EQ(f.server.deferred(), 0u);
  EXPECT_GE(f.server.duplicates(), 1);
  f.bus->unsubscribe(side);
}
