// The toy "physics" of the lockstep demo, shared by sb_clock and the demo participants
// (py_skills/skillbus/lockstep_demo.py computes the same): every value a process
// receives is folded into its state in the order it is handled, so any dependence on
// arrival order would change the digest.
#pragma once

#include <cstdint>

namespace skillbus::apps {

inline uint64_t demo_mix(uint64_t state, int64_t value) {
  state ^= static_cast<uint64_t>(value);
  state *= 0x100000001b3ULL;  // FNV-1a 64-bit prime
  state ^= state >> 29;
  return state;
}

}  // namespace skillbus::apps
