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
