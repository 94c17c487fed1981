#include "finger_watch.hpp"

#include <cmath>
#include <exception>

#include "skillbus_msgs/sim_state_t.hpp"

namespace skillbus::native {

bool finger_watch_holds(const FingerWatch& w, const uint8_t* payload, size_t n) {
  skillbus_msgs::sim_state_t s;
  try {  // (a negative count makes the generated decoder throw: Python's to judge)
    // Every byte, as Python's decoder wants it (trailing bytes: it refuses the state).
    if (s.decode(payload, 0, static_cast<int>(n)) != static_cast<int>(n)) return false;
  } catch (const std::exception&) {
    return false;
  }
  // (written so that NaN fails every test, as Python's checks refuse it)
  const double width = s.finger_width, force = s.finger_force, target = s.finger_width_target;
  if (!(width >= w.width_lo_m && width <= w.width_hi_m)) return false;
  if (!(target >= w.width_lo_m && target <= w.width_hi_m)) return false;
  if (!(force >= w.force_lo_n && force <= w.force_hi_n)) return false;
  const double width_um = width * 1e6;
  const double position = std::nearbyint(width_um);  // Python's round(): halves to even
  if (!(position >= static_cast<double>(w.position_lo_um) && position <= static_cast<double>(w.position_hi_um)))
    return false;
  if (!(std::abs(target * 1e6 - w.target_um) < 1.0)) return false;
  if (!(std::abs(width_um - w.target_um) > w.apart_um)) return false;
  return s.num_contacts > 0;
}

}  // namespace skillbus::native
