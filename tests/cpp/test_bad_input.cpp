// Random bytes and truncations of real messages, decoded as every message type, must
// be rejected cleanly (never crash, never read out of bounds under ASan/valgrind).
#include <gtest/gtest.h>

#include <random>

#include "skillbus/bus.hpp"
#include "skillbus_msgs/lockstep_ack_t.hpp"
#include "skillbus_msgs/lockstep_clock_t.hpp"
#include "skillbus_msgs/lockstep_join_t.hpp"
#include "skillbus_msgs/rpc_reply_t.hpp"
#include "skillbus_msgs/rpc_request_t.hpp"
#include "skillbus_msgs/test_sample_t.hpp"

using namespace skillbus;

template <class T>
void hammer(const T& valid) {
  std::mt19937 rng(12345);  // seeded: the same inputs every run
  const Bytes good = encode_msg(valid);
  T out;
  for (size_t n = 0; n < good.size(); ++n) EXPECT_FALSE(decode_msg(good.data(), n, out)) << "truncated to " << n;
  EXPECT_TRUE(decode_msg(good.data(), good.size(), out));
  for (int i = 0; i < 2000; ++i) {
    Bytes junk(rng() % 300);
    for (auto& b : junk) b = static_cast<uint8_t>(rng());
    if (i % 2 && junk.size() >= 8) std::copy(good.begin(), good.begin() + 8, junk.begin());  // right fingerprint
    decode_msg(junk.data(), junk.size(), out);  // must simply return
  }
}

TEST(BadInput, EveryTypeRejectsTruncationsAndSurvivesRandomBytes) {
  skillbus_msgs::test_sample_t s{};
  s.text = "abc";
  s.values = {1, 2};
  s.num_values = 2;
  s.rows = 2;
  s.cols = 2;
  s.matrix = {{1, 2}, {3, 4}};
  hammer(s);
  skillbus_msgs::lockstep_clock_t c{};
  c.participants = {"a", "b"};
  c.num_participants = 2;
  hammer(c);
  hammer(skillbus_msgs::lockstep_ack_t{});
  hammer(skillbus_msgs::lockstep_join_t{});
  skillbus_msgs::rpc_request_t q{};
  q.payload = {1, 2, 3};
  q.payload_size = 3;
  hammer(q);
  hammer(skillbus_msgs::rpc_reply_t{});
}

TEST(BadInput, AHugeClaimedArrayLengthIsRejectedWithoutAllocating) {
  // A clock claiming 2^31-1 counts in a 50-byte datagram: LCM's generated decode would
  // resize a vector to that length (gigabytes, a hang) unless the bindings are hardened
  // (lcmtypes/harden_cpp.cmake).
  skillbus_msgs::lockstep_clock_t c{};
  Bytes b = encode_msg(c);
  const size_t num_counts_at = 8 + (8 + 8 + 5 + 4) + 8 + 4;  // fingerprint, header, period, num_participants
  ASSERT_EQ(b.size(), num_counts_at + 4 + 1 + 5);            // num_counts, stop, stop_reason
  b[num_counts_at] = 0x7f;
  b[num_counts_at + 1] = b[num_counts_at + 2] = b[num_counts_at + 3] = 0xff;
  skillbus_msgs::lockstep_clock_t out;
  EXPECT_FALSE(decode_msg(b.data(), b.size(), out));
}
