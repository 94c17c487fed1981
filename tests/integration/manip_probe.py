"""Prints what the physics shows now, as JSON: every object's world pose (SB_SIM_STATE:
the ground truth), the articulated joints' positions and handle poses
(SB_ROBOT_ARTICULATION), the tool pose and the finger width
(tests/integration/test_manip_skills.py)."""

from __future__ import annotations

import json
import sys
import time

from skillbus.bus import open_bus
from skillbus.msgs import articulation_state_t, decode, sim_state_t
from skillbus.robot.articulation import articulation_channel
from skillbus.sim.messages import state_channel


def main() -> int:
    bus = open_bus()
    got: dict[str, object] = {}
    bus.subscribe(state_channel(), lambda ch, d: got.__setitem__("state", decode(sim_state_t, d)))
    bus.subscribe(articulation_channel(), lambda ch, d: got.__setitem__("joints", decode(articulation_state_t, d)))
    end = time.monotonic() + 20
    while len(got) < 2 and time.monotonic() < end:
        bus.handle(0.05)
    if len(got) < 2:
        print(json.dumps({"error": f"heard only {sorted(got)} within 20 s"}))
        return 1
    s, a = got["state"], got["joints"]
    print(json.dumps({
        "frame": s.header.frame,
        "objects": {o.name: list(o.pose) for o in s.objects},
        "tool": list(s.tool_pose), "finger_width": s.finger_width,
        "joints": {f"{j.object}/{j.joint}": {"position": j.position, "handle": list(j.handle_pose), "kind": j.kind,
                                             "lower": j.lower, "upper": j.upper} for j in a.joints},
    }))
    return 0


if __name__ == "__main__":
    sys.exit(main())
