// A watch on the simulated fingers, for the quiet-frame core (quiet_frames.hpp).
//
// The simulated gripper device (py_skills/skillbus/can/device_lockstep.py) holding an
// object has nothing to do in a frame whose physics state keeps the fingers as it last
// judged them: stalled on the object (the set-point taken, short of it, pushing with at
// least 0.9 of the force limit, touching something) and not moved far enough to send
// TPDO1. It hands the quiet-frame core these bounds; a frame whose newest sim_state_t
// breaks any of them, or does not decode, goes to Python, which judges it as ever.
// Every comparison is the one Python makes, in the same double arithmetic.
#pragma once

#include <cstddef>
#include <cstdint>

namespace skillbus::native {

struct FingerWatch {
  double width_lo_m = 0, width_hi_m = 0;  // finger_width and finger_width_target: a reading (inclusive)
  double force_lo_n = 0, force_hi_n = 0;  // finger_force (inclusive): pushing, and a reading
  int64_t position_lo_um = 0, position_hi_um = 0;  // round(finger_width * 1e6) (inclusive): no TPDO1 due
  double target_um = 0;  // |finger_width_target * 1e6 - target_um| < 1: the set-point taken
  double apart_um = 0;   // |finger_width * 1e6 - target_um| > apart_um: short of it
};

// Whether the sim_state_t in `payload` (a verified lockstep message) keeps within `w`
// and has a finger contact.
bool finger_watch_holds(const FingerWatch& w, const uint8_t* payload, size_t n);

}  // namespace skillbus::native
