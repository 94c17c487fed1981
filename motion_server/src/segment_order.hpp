// Private to motion_core: the states of a straight joint segment checked in halving order.
#pragma once

#include <cstdint>

namespace skillbus::motion {

// Whether valid(i) holds for every i in 1..n, asked coarse to fine: first the states at
// multiples of the largest power of two up to n, then the odd multiples of each smaller
// one (for n = 10: 8, 4, 2, 6, 10, 1, 3, 5, 7, 9). Every state is asked once, as in order,
// so a clear segment costs the same; a blocked one (the post in the middle of a move, a
// shortcut that cuts through it) is found after a few checks instead of halfway along.
// The answer is the same in any order: the plan does not change.
template <class Valid>
bool all_valid_coarse_to_fine(int n, Valid&& valid) {
  if (n < 1) return true;
  int64_t top = 1;  // (64-bit: i + 2 * stride stays in range for any int n)
  while (top <= n / 2) top *= 2;
  for (int64_t stride = top; stride >= 1; stride /= 2)
    for (int64_t i = stride; i <= n; i += 2 * stride)
      if (!valid(static_cast<int>(i))) return false;
  return true;
}

}  // namespace skillbus::motion
