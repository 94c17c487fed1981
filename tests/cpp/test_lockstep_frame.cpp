#include <gtest/gtest.h>

#include "skillbus/lockstep.hpp"
#include "skillbus/lockstep_frame.hpp"

#include <chrono>
#include <thread>
#include "skillbus_msgs/test_sample_t.hpp"

using namespace skillbus;

namespace {

Bytes stamped(int64_t frame, const std::string& sender, int32_t seq, int64_t value = 0) {
  skillbus_msgs::test_sample_t m{};
  m.header.frame = frame;
  m.header.sender = sender;
  m.header.seq = seq;
  m.i64 = value;
  return encode_msg(m);
}

ChannelCount count(const std::string& sender, const std::string& ch, int64_t frame, int32_t n) {
  ChannelCount c;
  c.sender = sender;
  c.channel = ch;
  c.frame = frame;
  c.count = n;
  return c;
}

}  // namespace

TEST(Stamp, ReadFromAnyMessageWithAHeaderFirst) {
  const Bytes b = stamped(42, "wm", 7);
  Stamp s;
  ASSERT_TRUE(peek_stamp(b.data(), b.size(), s));
  EXPECT_EQ(s.frame, 42);
  EXPECT_EQ(s.sender, "wm");
  EXPECT_EQ(s.seq, 7);
}

TEST(Stamp, RejectsTruncatedAndGarbage) {
  const Bytes b = stamped(1, "wm", 0);
  Stamp s;
  for (size_t n = 0; n < 30; ++n) EXPECT_FALSE(peek_stamp(b.data(), n, s)) << n;
  Bytes junk(64, 0xff);
  EXPECT_FALSE(peek_stamp(junk.data(), junk.size(), s));
}

TEST(FrameInbox, HandsOutInCanonicalOrderWhateverTheArrivalOrder) {
  BadInputCounter bad("t");
  FrameInbox inbox("me", bad);
  const std::vector<std::tuple<std::string, std::string, int32_t>> arrivals = {
      {"B", "p2", 1}, {"A", "p2", 0}, {"A", "p1", 1}, {"B", "p1", 0}};
  for (const auto& [ch, sender, seq] : arrivals) {
    const Bytes b = stamped(3, sender, seq);
    inbox.add(ch, b.data(), b.size());
  }
  const std::vector<ChannelCount> want = {count("p1", "A", 3, 1), count("p1", "B", 3, 1), count("p2", "A", 3, 1),
                                          count("p2", "B", 3, 1)};
  ASSERT_EQ(inbox.missing(want), "");
  auto out = inbox.take(want, 4);
  ASSERT_EQ(out.size(), 4u);
  std::vector<std::string> order;
  for (const auto& m : out) order.push_back(m.stamp.sender + "/" + std::to_string(m.stamp.seq) + "/" + m.channel);
  EXPECT_EQ(order, (std::vector<std::string>{"p1/0/B", "p1/1/A", "p2/0/A", "p2/1/B"}));
}

TEST(FrameInbox, NamesWhatIsMissing) {
  BadInputCounter bad("t");
  FrameInbox inbox("me", bad);
  const Bytes b = stamped(5, "p1", 0);
  inbox.add("SB_X", b.data(), b.size());
  EXPECT_EQ(inbox.missing({count("p1", "SB_X", 5, 2)}), "channel SB_X from sender p1 in frame 5: got 1 of 2");
}

TEST(FrameInbox, TheSenderOfAMissingMessageIsReadBackFromItsText) {
  BadInputCounter bad("t");
  FrameInbox inbox("me", bad);
  EXPECT_EQ(sender_of_missing(inbox.missing({count("arm_2", "SB_X", 7, 1)})), "arm_2");
  EXPECT_EQ(sender_of_missing("message lost on " + inbox.missing({count("p", "SB_Y", 0, 3)}) + " (noticed by q)"), "p");
  EXPECT_EQ(sender_of_missing("frame handler failed: boom"), "");
  EXPECT_EQ(sender_of_missing("text from sender without the frame"), "");
}

TEST(FrameInbox, DropsOwnDuplicateStaleAndUnstampedMessages) {
  BadInputCounter bad("t");
  FrameInbox inbox("me", bad);
  const Bytes own = stamped(1, "me", 0), a = stamped(1, "p", 0);
  inbox.add("A", own.data(), own.size());
  inbox.add("A", a.data(), a.size());
  inbox.add("A", a.data(), a.size());
  EXPECT_EQ(inbox.duplicates(), 1);
  EXPECT_EQ(inbox.take({count("p", "A", 1, 1)}, 2).size(), 1u);
  inbox.add("A", a.data(), a.size());  // frame 1 < floor 2
  EXPECT_EQ(inbox.stale(), 1);
  const uint8_t junk[5] = {1, 2, 3, 4, 5};
  inbox.add("A", junk, sizeof junk);
  EXPECT_EQ(bad.total(), 1);
}

TEST(Expectations, OnlySubscribedChannelsFromOthersWithMessages) {
  const std::vector<ChannelCount> announced = {count("me", "A", 1, 1), count("p", "A", 1, 2), count("p", "B", 1, 1),
                                               count("q", "A", 1, 0)};
  auto e = expectations_for(announced, {"A"}, "me");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].sender, "p");
  EXPECT_EQ(e[0].count, 2);
}

namespace {
// Keeps what is published.
class RecordingBus : public Bus {
 public:
  void publish(const std::string&, const void* data, size_t size) override {
    sent.emplace_back(static_cast<const uint8_t*>(data), static_cast<const uint8_t*>(data) + size);
  }
  int subscribe(const std::string&, Handler, int) override { return 0; }
  void unsubscribe(int) override {}
  bool handle(std::chrono::milliseconds) override { return false; }
  std::string url() const override { return "recording://"; }
  std::vector<Bytes> sent;
};
}  // namespace

// The outbox stamps a message by replacing its encoded header (it does not copy the
// message): the bytes are those of the message with the frame's header set, whatever
// header the message carried, and the message itself is left as it was.
TEST(FrameOutbox, StampsTheEncodedHeaderWithoutTouchingTheMessage) {
  RecordingBus bus;
  FrameOutbox out(bus, "physics");
  out.begin_frame(12, 240000000);
  std::vector<Bytes> expected;
  int32_t seq = 0;
  for (const std::string old_sender : {"", "sim", "physics", "a-much-longer-sender-name"}) {
    skillbus_msgs::test_sample_t m{};
    m.header.frame = 99;
    m.header.sender = old_sender;
    m.header.seq = 5;
    m.i64 = 1234567;
    m.text = "payload after the header";
    out.publish("SB_X", m);
    EXPECT_EQ(m.header.sender, old_sender);  // untouched
    skillbus_msgs::test_sample_t want = m;
    want.header.frame = 12;
    want.header.sim_time_ns = 240000000;
    want.header.sender = "physics";
    want.header.seq = seq++;
    expected.push_back(encode_msg(want));
  }
  EXPECT_EQ(bus.sent, expected);
}

// Wall-clock mode after a long frame: the frames it missed are not run back to back (a
// skill manager ticked a skill five times in 3 ms after a planner's expansion, and a
// process watching the world model could not see the robot between two shelves); the
// schedule starts again from the late frame, at the frame period.
TEST(WallClockParticipant, AfterALongFrameTheMissedFramesAreNotRunBackToBack) {
  auto bus = open_bus("memq://");
  ParticipantConfig cfg;
  cfg.name = "p";
  cfg.mode = ClockMode::WallClock;
  cfg.wall_frame_period_ns = 20'000'000;
  cfg.wall_frames = 8;
  LockstepParticipant p(*bus, cfg);
  std::vector<std::chrono::steady_clock::time_point> at;
  p.on_frame = [&](int64_t frame, int64_t) {
    at.push_back(std::chrono::steady_clock::now());
    if (frame == 2) std::this_thread::sleep_for(std::chrono::milliseconds(200));  // ten frames' time
  };
  const RunResult r = p.run();
  ASSERT_EQ(r.frames, 8);
  ASSERT_EQ(at.size(), 8u);
  for (size_t i = 4; i < at.size(); ++i)
    EXPECT_GE(at[i] - at[i - 1], std::chrono::milliseconds(15)) << "frame " << i << " ran right after frame " << i - 1;
}
