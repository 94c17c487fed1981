// Channel names with several robots: a robot's own channels go under its name, the shared
// ones do not; robot names that cannot be part of a channel are refused.
#include <gtest/gtest.h>

#include <cstdlib>
#include <stdexcept>
#include <vector>

#include "skillbus/bus.hpp"

using namespace skillbus;

namespace {
struct RobotReset {
  ~RobotReset() {
    set_robot("");
    ::unsetenv("SKILLBUS_ROBOT");
    ::unsetenv("SKILLBUS_NAMESPACE");
  }
};
}  // namespace

TEST(Channels, ARobotsOwnChannelsGoUnderItsName) {
  RobotReset reset;
  for (const char* own : {"SB_ROBOT_ARM_STATE", "SB_ROBOT_ARM_CMD", "SB_SKILL_REQ", "SB_SKILL_PROGRESS",
                          "SB_SKPROC_SKILLS_REQ", "SB_MOTION_REP", "SB_CAN_SYNC", "SB_SIM_STATE",
                          "SB_SIM_GRIPPER_CMD", "SB_SIM_CMD_REPLY", "SB_SIM_ATTACH", "SB_ROBOT_ARTICULATION",
                          "SB_SKILL_MANAGER", "SB_SKILL_HEARTBEAT"}) {
    EXPECT_TRUE(robot_scoped(own)) << own;
    EXPECT_EQ(robot_channel(own, "r2"), std::string("r2/") + own);
    EXPECT_EQ(robot_channel(own, ""), own);
  }
  for (const char* shared : {"SB_WM_REQ", "SB_WM_CHANGES", "SB_WM_TXN", "SB_LOCKSTEP_CLOCK", "SB_LOCKSTEP_ACK",
                             "SB_LOCKSTEP_END", "SB_SIM_REQ", "SB_SIM_REP", "SB_MANAGERS", "SB_MANAGERS_PROBE",
                             "SB_LOG_MARK"}) {
    EXPECT_FALSE(robot_scoped(shared)) << shared;
    EXPECT_EQ(robot_channel(shared, "r2"), shared);
  }
}

TEST(Channels, TheProcesssRobotComesFromSetRobotElseTheEnvironment) {
  RobotReset reset;
  ::setenv("SKILLBUS_ROBOT", "envbot", 1);
  EXPECT_EQ(current_robot(), "envbot");
  EXPECT_EQ(channel("SB_ROBOT_ARM_CMD"), "envbot/SB_ROBOT_ARM_CMD");
  set_robot("r1");
  EXPECT_EQ(current_robot(), "r1");
  EXPECT_EQ(channel("SB_SKILL_REQ"), "r1/SB_SKILL_REQ");
  EXPECT_EQ(channel("SB_WM_REQ"), "SB_WM_REQ");
  ::setenv("SKILLBUS_NAMESPACE", "lab_", 1);  // a whole system apart: in front of everything
  EXPECT_EQ(channel("SB_SKILL_REQ"), "lab_r1/SB_SKILL_REQ");
  EXPECT_EQ(channel("SB_WM_REQ"), "lab_SB_WM_REQ");
  set_robot("");  // explicitly none, whatever the environment says
  EXPECT_EQ(channel("SB_SKILL_REQ"), "lab_SB_SKILL_REQ");
}

TEST(Channels, RobotNamesThatCannotNameAChannelAreRefused) {
  RobotReset reset;
  for (const char* good : {"r1", "left_arm", "A", "r23456789012345678901234"}) EXPECT_TRUE(valid_robot_name(good)) << good;
  for (const char* bad : {"", "1r", "r/2", "r 2", "r-2", "_r", "r.2", "ü", "r234567890123456789012345"}) {
    EXPECT_FALSE(valid_robot_name(bad)) << bad;
    if (*bad) {
      EXPECT_THROW(set_robot(bad), std::invalid_argument) << bad;
    }
  }
  EXPECT_EQ(current_robot(), "");  // a refused name changed nothing
}

// LCM ends channel names at 63 bytes: a longer one registers, subscribes and then never
// carries a message, so it fails where it is made, saying which part is long.
TEST(Channels, ANameLongerThanLcmAllowsIsRefusedWhereItIsMade) {
  RobotReset reset;
  const std::string longest(49, 'P');  // SB_SKPROC_ + 49 + _REQ = 63 bytes
  EXPECT_EQ(channel("SB_SKPROC_" + longest + "_REQ").size(), 63u);
  try {
    channel("SB_SKPROC_" + longest + "Q_REQ");
    ADD_FAILURE() << "a 64-byte channel name was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("64 bytes"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("63"), std::string::npos) << e.what();
  }
  set_robot("r2");
  try {
    channel("SB_SKPROC_" + longest + "_REQ");
    ADD_FAILURE() << "a 66-byte channel name was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("robot r2"), std::string::npos) << e.what();
  }
  set_robot("");
  ::setenv("SKILLBUS_NAMESPACE", std::string(60, 'N').c_str(), 1);
  EXPECT_THROW(channel("SB_WM_REQ"), std::invalid_argument);
}

TEST(Channels, TheLimitIsInBytesAsLcmCountsThem) {
  RobotReset reset;
  std::string fits, too_long;
  for (int i = 0; i < 31; ++i) fits += "\xc3\xa9";  // é: 31 characters of 2 bytes, and one more byte
  fits += "x";
  too_long = fits.substr(0, 62) + "\xc3\xa9";  // 32 characters, 64 bytes
  EXPECT_TRUE(channel_too_long(fits).empty());  // (as LCM counts: bytes)
  EXPECT_FALSE(channel_too_long(too_long).empty());
  EXPECT_THROW(refuse_long_channel(too_long), BusError);
}

// Cyclone DDS 0.10 takes letters, digits, _ and / in a topic name, not a leading digit; before,
// such names ran on LCM and failed on DDS at their first use.
TEST(Channels, ANameADdsTopicRefusesIsRefusedOnEitherTransport) {
  RobotReset reset;
  for (const char* bad : {"SB_SKPROC_MY-ARM_REQ", "SB_X.Y", "SB_\xc3\xa9", "9SB_X", "SB X"})
    EXPECT_THROW(channel(bad), std::invalid_argument) << bad;
  ::setenv("SKILLBUS_NAMESPACE", "lab-", 1);
  try {
    channel("SB_WM_REQ");
    ADD_FAILURE() << "a namespace with '-' was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("$SKILLBUS_NAMESPACE is 'lab-'"), std::string::npos) << e.what();
  }
  ::setenv("SKILLBUS_NAMESPACE", "lab_", 1);
  set_robot("r2");
  EXPECT_EQ(channel("SB_SKILL_REQ"), "lab_r2/SB_SKILL_REQ");
}

TEST(Channels, EveryBusRefusesAChannelLcmCannotCarry) {
  auto bus = open_bus("memq://");
  const std::string too_long(64, 'C');
  EXPECT_THROW(bus->subscribe(too_long, [](const std::string&, const uint8_t*, size_t) {}), BusError);
  EXPECT_THROW(bus->publish(too_long, "x", 1), BusError);
}

// Before, a message larger than a receiver reassembles (16 MiB, as LCM) was sent and
// dropped by every receiver: an RPC request that large timed out without a word on why.
TEST(Channels, EveryBusRefusesAMessageLargerThanAReceiverReassembles) {
  auto bus = open_bus("memq://");
  size_t got = 0;
  bus->subscribe("SB_BIG", [&](const std::string&, const uint8_t*, size_t n) { got = n; });
  const std::vector<uint8_t> big(kMaxMessageBytes + 1);
  try {
    bus->publish("SB_BIG", big.data(), big.size());
    ADD_FAILURE() << "a message over the limit was sent";
  } catch (const BusError& e) {
    // (the size on the wire: with a key, the signature's trailer counts too)
    EXPECT_NE(std::string(e.what()).find("bytes on SB_BIG: over the 16777216 bytes"), std::string::npos) << e.what();
  }
  bus->publish("SB_BIG", big.data(), kMaxMessageBytes - 1024);
  bus->handle(std::chrono::milliseconds(1000));
  EXPECT_EQ(got, kMaxMessageBytes - 1024);
}
