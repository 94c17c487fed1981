#include <gtest/gtest.h>

#include "dds_bus.hpp"
#include "skillbus/bus.hpp"
#include "skillbus/faulty_bus.hpp"
#include "skillbus_msgs/test_sample_t.hpp"

using namespace skillbus;
using namespace std::chrono_literals;

TEST(Bus, MemqDeliversToSubscribersOfThatChannelOnly) {
  auto bus = open_bus("memq://");
  std::vector<std::string> got;
  bus->subscribe("A", [&](const std::string& ch, const uint8_t* d, size_t n) { got.push_back(ch + ":" + std::string(d, d + n)); });
  bus->publish("A", "one", 3);
  bus->publish("B", "two", 3);
  bus->publish("A", "three", 5);
  while (bus->handle(0ms)) {
  }
  EXPECT_EQ(got, (std::vector<std::string>{"A:one", "A:three"}));
}

TEST(Bus, QueueCapacityKeepsBursts) {
  // LCM's default queue of 30 would drop most of this burst.
  auto bus = open_bus("memq://");
  int got = 0;
  bus->subscribe("A", [&](const std::string&, const uint8_t*, size_t) { ++got; });
  for (int i = 0; i < 500; ++i) bus->publish("A", "x", 1);
  while (bus->handle(0ms)) {
  }
  EXPECT_EQ(got, 500);
}

TEST(Bus, UnsubscribeStopsDelivery) {
  auto bus = open_bus("memq://");
  int got = 0;
  int id = bus->subscribe("A", [&](const std::string&, const uint8_t*, size_t) { ++got; });
  bus->unsubscribe(id);
  bus->publish("A", "x", 1);
  bus->handle(10ms);
  EXPECT_EQ(got, 0);
}

TEST(Bus, UnknownSchemeIsAClearError) {
  try {
    open_bus("carrier-pigeon://coop");
    FAIL() << "expected BusError";
  } catch (const BusError& e) {
    EXPECT_NE(std::string(e.what()).find("carrier-pigeon://coop"), std::string::npos);
  }
  EXPECT_THROW(open_bus("dds://999"), BusError);  // (a domain out of range)
}

TEST(Bus, UrlFromEnvironmentWhenNoneGiven) {
  setenv("SKILLBUS_BUS_URL", "memq://", 1);
  EXPECT_EQ(resolve_bus_url(), "memq://");
  EXPECT_EQ(resolve_bus_url("udpm://239.255.76.67:7700?ttl=0"), "udpm://239.255.76.67:7700?ttl=0");
  unsetenv("SKILLBUS_BUS_URL");
  EXPECT_EQ(resolve_bus_url(), kDefaultBusUrl);
}

TEST(Bus, TypedRoundTripAndRejectsOtherTypes) {
  auto bus = open_bus("memq://");
  skillbus_msgs::test_sample_t in{};
  in.text = "hello";
  in.values = {1, 2, 3};
  in.num_values = 3;
  bool ok = false;
  skillbus_msgs::test_sample_t out;
  bus->subscribe("T", [&](const std::string&, const uint8_t* d, size_t n) { ok = decode_msg(d, n, out); });
  publish_msg(*bus, "T", in);
  bus->handle(100ms);
  ASSERT_TRUE(ok);
  EXPECT_EQ(out.text, "hello");
  EXPECT_EQ(out.values, (std::vector<int64_t>{1, 2, 3}));
  const uint8_t garbage[16] = {1, 2, 3};
  EXPECT_FALSE(decode_msg(garbage, sizeof garbage, out));
}

TEST(FaultyBus, DropsEveryNthPublish) {
  auto bus = std::make_unique<DropEveryNthBus>(open_bus("memq://"), 3);
  int got = 0;
  bus->subscribe("A", [&](const std::string&, const uint8_t*, size_t) { ++got; });
  for (int i = 0; i < 9; ++i) bus->publish("A", "x", 1);
  while (bus->handle(0ms)) {
  }
  EXPECT_EQ(got, 6);
  EXPECT_EQ(bus->dropped(), 3);
}

// Private to the LCM backend, but its rule is part of the wire contract (docs/transport.md).
namespace skillbus {
int lcm_lane_of(const std::string& channel);
std::string lcm_lane1_url(const std::string& url);
std::string lcm_url_with_receive_buffer(const std::string& url, long rmem_max);
}  // namespace skillbus

TEST(LcmLanes, ManyToOneChannelsUsePortPlusOne) {
  EXPECT_EQ(lcm_lane_of("SB_LOCKSTEP_ACK"), 1);
  EXPECT_EQ(lcm_lane_of("R2/SB_LOCKSTEP_JOIN"), 1);
  EXPECT_EQ(lcm_lane_of("SB_LOCKSTEP_CLOCK"), 0);
  EXPECT_EQ(lcm_lane1_url("udpm://239.255.76.67:7667?ttl=0"), "udpm://239.255.76.67:7668?ttl=0");
  EXPECT_EQ(lcm_lane1_url("udpm://239.1.2.3"), "udpm://239.1.2.3:7668");
  EXPECT_EQ(lcm_lane1_url("memq://"), "");
  // A port that leaves no room for lane 1 is refused at once (before: the first ack failed,
  // and a receiver of port+1 bound a wrapped port).
  for (const char* bad : {"udpm://239.1.2.3:65535", "udpm://239.1.2.3:0", "udpm://239.1.2.3:99999999999"})
    EXPECT_THROW(lcm_lane1_url(bad), BusError) << bad;
  EXPECT_EQ(lcm_lane1_url("udpm://239.1.2.3:65534"), "udpm://239.1.2.3:65535");
}

TEST(LcmUrl, AsksForALargeReceiveBufferUnlessTheUrlNamesOne) {
  EXPECT_EQ(lcm_url_with_receive_buffer("udpm://239.255.76.67:7667?ttl=0", 8L << 20),
            "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304");
  EXPECT_EQ(lcm_url_with_receive_buffer("udpm://239.1.2.3", 1000000), "udpm://239.1.2.3?recv_buf_size=1000000");
  EXPECT_EQ(lcm_url_with_receive_buffer("udpm://239.1.2.3", -1), "udpm://239.1.2.3?recv_buf_size=4194304");
  EXPECT_EQ(lcm_url_with_receive_buffer("udpm://239.1.2.3?recv_buf_size=9", 1 << 30), "udpm://239.1.2.3?recv_buf_size=9");
  EXPECT_EQ(lcm_url_with_receive_buffer("memq://", 1 << 30), "memq://");
}

TEST(LcmLanes, MemqHasOneLaneSoAcksStillArrive) {
  auto bus = open_bus("memq://");
  int got = 0;
  bus->subscribe("SB_LOCKSTEP_ACK", [&](const std::string&, const uint8_t*, size_t) { ++got; });
  bus->publish("SB_LOCKSTEP_ACK", "a", 1);
  bus->handle(std::chrono::milliseconds(100));
  EXPECT_EQ(got, 1);
}

// The dds:// URL (common/src/dds_bus.hpp, private to skillbus_common; the Python twin:
// skillbus.dds.parse_url).

TEST(DdsUrl, TheDomainAndTheOptionsAreRead) {
  const auto u = parse_dds_url("dds://7");
  EXPECT_EQ(u.domain, 7);
  EXPECT_TRUE(u.peers.empty());
  EXPECT_EQ(u.interface, "127.0.0.1");
  const auto v = parse_dds_url("dds://0?peers=10.0.0.2,robot-b&interface=10.0.0.1&state=best-effort");
  EXPECT_EQ(v.peers, (std::vector<std::string>{"10.0.0.2", "robot-b"}));
  EXPECT_EQ(v.interface, "10.0.0.1");
  EXPECT_TRUE(v.state_best_effort);
}

TEST(DdsUrl, AWrongUrlIsAnErrorNamingIt) {
  for (const char* bad : {"dds://", "dds://x", "dds://233", "dds://1?colour=red", "dds://1?state=sometimes"}) {
    try {
      parse_dds_url(bad);
      ADD_FAILURE() << bad;
    } catch (const BusError& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}

TEST(DdsUrl, AnotherHostNeedsTheNetworkAllowed) {
  unsetenv("SKILLBUS_NETWORK");
  EXPECT_NO_THROW(check_dds_local(parse_dds_url("dds://1?peers=localhost,127.0.0.2"), "dds://1"));
  EXPECT_THROW(check_dds_local(parse_dds_url("dds://1?interface=10.0.0.1"), "dds://1"), BusError);
  EXPECT_THROW(check_dds_local(parse_dds_url("dds://1?peers=robot-b"), "dds://1"), BusError);
  setenv("SKILLBUS_NETWORK", "veth0", 1);
  EXPECT_NO_THROW(check_dds_local(parse_dds_url("dds://1?peers=robot-b"), "dds://1"));
  unsetenv("SKILLBUS_NETWORK");
}

// A ROS 2 shell's $CYCLONEDDS_URI was used as it was: the robot's bus went on the network
// without anyone saying so. Refused before any participant is made (nothing is sent).
TEST(DdsUrl, ACycloneConfigurationFromElsewhereNeedsTheNetworkAllowed) {
  ::setenv("CYCLONEDDS_URI", "file:///etc/ros/cyclone.xml", 1);
  ::unsetenv("SKILLBUS_DDS_CONFIG");
  ::unsetenv("SKILLBUS_NETWORK");
  try {
    open_bus("dds://5");
    ADD_FAILURE() << "a foreign $CYCLONEDDS_URI was used";
  } catch (const BusError& e) {
    EXPECT_NE(std::string(e.what()).find("$CYCLONEDDS_URI is set (file:///etc/ros/cyclone.xml)"), std::string::npos)
        << e.what();
  }
  ::unsetenv("CYCLONEDDS_URI");
}
