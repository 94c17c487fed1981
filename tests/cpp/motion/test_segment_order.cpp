// all_valid_coarse_to_fine: a segment's states checked coarse to fine give the same answer
// as in order, each state asked once (motion_server/src/segment_order.hpp).
#include <gtest/gtest.h>

#include <climits>
#include <random>
#include <set>
#include <vector>

#include "segment_order.hpp"

using skillbus::motion::all_valid_coarse_to_fine;

TEST(SegmentOrder, EveryStateIsAskedOnceCoarseToFine) {
  std::vector<int> asked;
  EXPECT_TRUE(all_valid_coarse_to_fine(10, [&](int i) { asked.push_back(i); return true; }));
  EXPECT_EQ(asked, (std::vector<int>{8, 4, 2, 6, 10, 1, 3, 5, 7, 9}));
  for (int n : {1, 2, 3, 7, 8, 9, 63, 64, 65, 100, 257}) {
    std::multiset<int> seen;
    EXPECT_TRUE(all_valid_coarse_to_fine(n, [&](int i) { seen.insert(i); return true; }));
    ASSERT_EQ(seen.size(), static_cast<size_t>(n)) << n;
    for (int i = 1; i <= n; ++i) EXPECT_EQ(seen.count(i), 1u) << "n " << n << " state " << i;
  }
  EXPECT_TRUE(all_valid_coarse_to_fine(0, [&](int) { ADD_FAILURE() << "asked with no state"; return false; }));
  int first = 0;  // the largest n starts at the largest power of two under it, without overflow
  EXPECT_FALSE(all_valid_coarse_to_fine(INT_MAX, [&](int i) { first = i; return false; }));
  EXPECT_EQ(first, 1 << 30);
}

TEST(SegmentOrder, TheAnswerIsTheOneInOrderAndABlockInTheMiddleIsFoundAtOnce) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 2000; ++trial) {
    const int n = 1 + static_cast<int>(rng() % 200);
    std::vector<bool> blocked(static_cast<size_t>(n) + 1, false);
    const int blocks = static_cast<int>(rng() % 3);  // none, one or two blocked stretches
    for (int b = 0; b < blocks; ++b) {
      const int from = 1 + static_cast<int>(rng() % n);
      const int len = 1 + static_cast<int>(rng() % 20);
      for (int i = from; i <= std::min(n, from + len - 1); ++i) blocked[static_cast<size_t>(i)] = true;
    }
    bool in_order = true;
    for (int i = 1; i <= n; ++i) in_order = in_order && !blocked[static_cast<size_t>(i)];
    EXPECT_EQ(all_valid_coarse_to_fine(n, [&](int i) { return !blocked[static_cast<size_t>(i)]; }), in_order);
  }
  int asked = 0;  // a post halfway along a 200-state move (90-110): found at the fifth check (96), not the 90th
  EXPECT_FALSE(all_valid_coarse_to_fine(200, [&](int i) { ++asked; return i < 90 || i > 110; }));
  EXPECT_EQ(asked, 5);
}
