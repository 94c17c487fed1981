// Message authentication in C++ (skillbus/auth.hpp): what verifies, every way a message
// is refused and counted, the policy's patterns, and a message sealed by the Python
// implementation (the same bytes on the wire).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdio>
#include <fstream>

#include "skillbus/auth.hpp"

using namespace skillbus;
using namespace skillbus::auth;

namespace {

Key key_of(uint8_t first) {
  Key k(32);
  for (size_t i = 0; i < k.size(); ++i) k[i] = static_cast<uint8_t>(first + i);
  return k;
}

int64_t g_now = 0;
int64_t fake_clock() { return g_now; }

struct Opened {
  bool ok;
  size_t payload;
  std::string identity;
  Reason reason;
};

Opened open(Opener& o, const std::string& ch, const Bytes& data) {
  Opened r{};
  std::string why;
  r.ok = o.open(ch, data.data(), data.size(), r.payload, r.identity, r.reason, why);
  return r;
}

Bytes bytes_of_hex(const std::string& hex) {
  Bytes b;
  for (size_t i = 0; i < hex.size(); i += 2) b.push_back(static_cast<uint8_t>(std::stoi(hex.substr(i, 2), nullptr, 16)));
  return b;
}

}  // namespace

TEST(Auth, ASealedMessageOpensToItsPayloadAndSender) {
  Sealer s(key_of(0), "wm");
  Opener o({key_of(0)});
  const Bytes sealed = s.seal("SB_X", "payload", 7);
  const Opened r = open(o, "SB_X", sealed);
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.payload, 7u);
  EXPECT_EQ(r.identity, "wm");
  EXPECT_EQ(o.stats().ok, 1u);
}

TEST(Auth, WhatDoesNotVerifyIsRefusedAndCounted) {
  Sealer s(key_of(0), "wm");
  Opener o({key_of(0)});
  const std::string plain = "payload";
  EXPECT_EQ(open(o, "SB_X", Bytes(plain.begin(), plain.end())).reason, Reason::Unsigned);
  Bytes changed = s.seal("SB_X", "payload", 7);
  changed[0] = 'P';
  EXPECT_EQ(open(o, "SB_X", changed).reason, Reason::BadMac);
  Sealer other(key_of(1), "wm");
  EXPECT_EQ(open(o, "SB_X", other.seal("SB_X", "payload", 7)).reason, Reason::BadMac);
  EXPECT_EQ(open(o, "SB_Y", s.seal("SB_X", "payload", 7)).reason, Reason::BadMac);  // moved channel
  Bytes tail = s.seal("SB_X", "payload", 7);
  tail.erase(tail.begin(), tail.begin() + 20);  // only the end: the lengths do not add up
  EXPECT_EQ(open(o, "SB_X", tail).reason, Reason::Unsigned);
  EXPECT_EQ(open(o, "SB_X", Bytes{}).reason, Reason::Unsigned);
  EXPECT_EQ(o.stats().ok, 0u);
  EXPECT_EQ(o.stats().total_rejected(), 6u);
  EXPECT_EQ(o.stats().rejected.at("bad_mac"), 3u);
}

TEST(Auth, ReplaysAreRefusedEvenOutOfOrderAndStaleMessagesToo) {
  Sealer s(key_of(0), "skills");
  Opener o({key_of(0)});
  const Bytes a = s.seal("SB_X", "a", 1), b = s.seal("SB_X", "b", 1), c = s.seal("SB_X", "c", 1);
  EXPECT_TRUE(open(o, "SB_X", c).ok);
  EXPECT_TRUE(open(o, "SB_X", a).ok);  // late but new
  EXPECT_EQ(open(o, "SB_X", a).reason, Reason::Replayed);
  EXPECT_EQ(open(o, "SB_X", c).reason, Reason::Replayed);
  EXPECT_TRUE(open(o, "SB_X", b).ok);
  // 31 s later everything sent now is stale.
  g_now = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
              .count() +
          31'000'000'000LL;
  o.clock_ns = fake_clock;
  EXPECT_EQ(open(o, "SB_X", s.seal("SB_X", "d", 1)).reason, Reason::Stale);
}

TEST(Auth, ThePolicyDecidesWhoSendsOnAChannel) {
  const Policy p = Policy::parse("SB_LOCKSTEP_CLOCK sim\nSB_SKPROC_*_REQ skill_mgr\nSB_*_REQ *\n", "test");
  EXPECT_TRUE(p.allows("sim", "SB_LOCKSTEP_CLOCK"));
  EXPECT_FALSE(p.allows("operator", "SB_LOCKSTEP_CLOCK"));
  EXPECT_TRUE(p.allows("skill_mgr", "SB_SKPROC_SKILLS_REQ"));
  EXPECT_FALSE(p.allows("operator", "SB_SKPROC_SKILLS_REQ"));
  EXPECT_TRUE(p.allows("operator", "SB_WM_REQ"));
  EXPECT_FALSE(p.allows("operator", "SB_UNLISTED"));
  EXPECT_THROW(Policy::parse("SB_X\n", "test"), BusError);
  EXPECT_THROW(Policy::parse("SB-X a\n", "test"), BusError);
  auto policy = std::make_shared<const Policy>(p);
  Opener o({key_of(0)}, policy);
  Sealer s(key_of(0), "operator");
  EXPECT_EQ(open(o, "SB_LOCKSTEP_CLOCK", s.seal("SB_LOCKSTEP_CLOCK", "x", 1)).reason, Reason::Forbidden);
  EXPECT_TRUE(open(o, "SB_WM_REQ", s.seal("SB_WM_REQ", "x", 1)).ok);
}

TEST(Auth, APolicyRuleWithoutARobotCoversThatChannelOfEveryRobot) {
  const Policy p = Policy::parse("r2/SB_ROBOT_ARM_CMD r2_skills\nSB_ROBOT_ARM_CMD skills\n", "test");
  EXPECT_TRUE(p.allows("r2_skills", "r2/SB_ROBOT_ARM_CMD"));
  EXPECT_FALSE(p.allows("r2_skills", "r1/SB_ROBOT_ARM_CMD"));  // another robot's arm
  EXPECT_TRUE(p.allows("skills", "r1/SB_ROBOT_ARM_CMD"));
  EXPECT_TRUE(p.allows("skills", "SB_ROBOT_ARM_CMD"));
  EXPECT_FALSE(p.allows("skills", "r2/SB_ROBOT_ARM_CMD"));     // the first rule that matches decides
}

TEST(Auth, GlobPatterns) {
  EXPECT_TRUE(glob_match("*", ""));
  EXPECT_TRUE(glob_match("SB_*_REQ", "SB_A_B_REQ"));
  EXPECT_FALSE(glob_match("SB_*_REQ", "SB_A_REP"));
  EXPECT_TRUE(glob_match("a*b*c", "aXbYbc"));
  EXPECT_FALSE(glob_match("abc", "abcd"));
}

TEST(Auth, AMessageSealedByThePythonImplementationVerifies) {
  // skillbus.auth.Sealer(bytes(range(32)), "skills", clock=lambda: 1_700_000_000 * 10**9)
  //   .seal("SB_X", b"payload")
  const Bytes sealed = bytes_of_hex(
      "7061796c6f616406736b696c6c7300002a36fe9c9717010000000000000000002a36fe9c971749b3fb4dbc9ff6aa8c77566c0ef6a1148153a0"
      "ec0804ab2b4eec02ddd66c5fcd3f0053424131");
  Opener o({key_of(0)});
  g_now = 1'700'000'000'000'000'000LL;
  o.clock_ns = fake_clock;
  const Opened r = open(o, "SB_X", sealed);
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.identity, "skills");
  EXPECT_EQ(std::string(sealed.begin(), sealed.begin() + static_cast<long>(r.payload)), "payload");
}

TEST(Auth, KeyFilesMustBePrivate) {
  const std::string path = ::testing::TempDir() + "/skillbus_test.key";
  {
    std::ofstream f(path);
    f << "# a test key\n000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f\n";
  }
  ::chmod(path.c_str(), 0644);
  EXPECT_THROW(load_keys(path), BusError);
  ::chmod(path.c_str(), 0600);
  const auto keys = load_keys(path);
  ASSERT_EQ(keys.size(), 1u);
  EXPECT_EQ(keys[0], key_of(0));
  std::remove(path.c_str());
  EXPECT_THROW(load_keys(path), BusError);
}

TEST(Auth, TheBusDeliversOnlyWhatVerifies) {
  auto memq = open_bus("memq://");
  Bus& transport = *memq;  // (what an outsider without the key publishes on)
  AuthenticatedBus bus(std::move(memq), {key_of(0)}, "wm", nullptr);
  std::vector<std::string> got;
  bus.subscribe("SB_X", [&](const std::string&, const uint8_t* d, size_t n) { got.emplace_back(d, d + n); });
  bus.publish("SB_X", "signed", 6);
  transport.publish("SB_X", "forged", 6);
  while (bus.handle(std::chrono::milliseconds(50))) {
  }
  EXPECT_EQ(got, std::vector<std::string>{"signed"});
  ASSERT_NE(stats_of(bus), nullptr);
  EXPECT_EQ(stats_of(bus)->ok, 1u);
  EXPECT_EQ(stats_of(bus)->rejected.at("unsigned"), 1u);
}

// A process may not send what the policy does not let it: every receiver would drop it
// (and a lockstep frame would wait for it, then fail as "message lost"); the send fails
// at once, naming the policy, the identity and the channel.
TEST(Auth, SendingWhatThePolicyForbidsFailsAtTheSender) {
  auto policy = std::make_shared<const Policy>(Policy::parse("SB_CAMERA_CLOUD sim\nSB_*_REQ *\n", "deploy/policy.conf"));
  AuthenticatedBus bus(open_bus("memq://"), {key_of(0)}, "skills", policy);
  bus.publish("SB_WM_REQ", "ok", 2);  // allowed to everyone
  try {
    bus.publish("SB_CAMERA_CLOUD", "no", 2);
    FAIL() << "published";
  } catch (const BusError& e) {
    EXPECT_STREQ(e.what(), "the bus policy deploy/policy.conf does not let 'skills' send on SB_CAMERA_CLOUD: every "
                           "receiver would drop it (add a rule for it; docs/security.md)");
  }
  EXPECT_THROW(bus.publish("SB_NOBODY", "no", 2), BusError);  // (no rule: refused)
  AuthenticatedBus sim(open_bus("memq://"), {key_of(0)}, "sim", policy);
  sim.publish("SB_CAMERA_CLOUD", "ok", 2);
}

TEST(Auth, TheReplayWindowSpansWords) {
  // Counters far apart (several 64-bit words of the window): each is taken once, a skipped
  // one late is taken, and everything beyond the window's 4,096 is refused.
  Sealer s(key_of(0), "skills");
  Opener o({key_of(0)});
  std::vector<Bytes> sealed;
  for (int i = 0; i < 5000; ++i) sealed.push_back(s.seal("SB_X", "m", 1));
  for (int i : {0, 1, 64, 65, 130, 700}) EXPECT_TRUE(open(o, "SB_X", sealed[i]).ok) << i;
  for (int i : {0, 1, 64, 65, 130, 700}) EXPECT_EQ(open(o, "SB_X", sealed[i]).reason, Reason::Replayed) << i;
  EXPECT_TRUE(open(o, "SB_X", sealed[129]).ok);  // never seen: late, within the window
  EXPECT_TRUE(open(o, "SB_X", sealed[4999]).ok);
  EXPECT_EQ(open(o, "SB_X", sealed[700]).reason, Reason::Replayed);  // now beyond the window
  EXPECT_EQ(open(o, "SB_X", sealed[800]).reason, Reason::Replayed);  // (never seen, but too old to tell)
  EXPECT_TRUE(open(o, "SB_X", sealed[4000]).ok);
  EXPECT_EQ(open(o, "SB_X", sealed[4000]).reason, Reason::Replayed);
}

// Before, a longer identity was cut to 255 bytes: receivers saw another identity than the
// policy's and dropped everything as forbidden, while the sender's own check passed.
TEST(Auth, AnIdentityTheTrailerCannotHoldIsRefusedNotCut) {
  EXPECT_THROW(Sealer(key_of(0), std::string(256, 'i')), BusError);
  EXPECT_THROW(Sealer(key_of(0), ""), BusError);
  EXPECT_NO_THROW(Sealer(key_of(0), std::string(255, 'i')));
  EXPECT_THROW(Policy::parse("SB_X " + std::string(256, 'y') + "\n", "test"), BusError);
}
