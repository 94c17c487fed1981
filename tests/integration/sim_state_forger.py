"""Publishes physics states (sim_state_t on SB_SIM_STATE) as a forger on the bus would:
lockstep-stamped like the physics server's, with the fingers' values given. For
test_untrusted_gripper.py.

Usage: sim_state_forger.py FIELD=VALUE:COUNT ...
  e.g. finger_width=0.04:1 finger_width=inf:10 finger_force=nan:10
Each argument publishes COUNT states, 1 ms apart, in the order given; FIELD is
finger_width, finger_force or finger_width_target, VALUE anything float() reads (inf,
-inf, nan, 1e300); the other two fields keep a sane value (width 40 mm, target 80 mm,
force 0). Prints {"sent": N} at the end."""

from __future__ import annotations

import json
import sys
import time

from skillbus.bus import open_bus
from skillbus.msgs import header_t, sim_state_t
from skillbus.sim.messages import state_channel


def main() -> int:
    bus = open_bus()
    sent = 0
    for arg in sys.argv[1:]:
        field, _, rest = arg.partition("=")
        value, _, count = rest.rpartition(":")
        for _ in range(int(count)):
            s = sim_state_t()
            h = header_t()
            h.frame, h.sim_time_ns, h.sender, h.seq = sent, sent * 10_000_000, "forger", 0
            s.header = h
            s.finger_width, s.finger_force, s.finger_width_target = 0.04, 0.0, 0.08
            setattr(s, field, float(value))
            bus.publish(state_channel(), s.encode())
            sent += 1
            time.sleep(0.001)
    print(json.dumps({"sent": sent}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
